"""Every number the prose states has a source: the code, the paper, or a chosen constant.

A figure the code computes reaches the prose only through the code: a code cell writes the
sentence with ``display(Markdown(f"... {value:.2f} m ..."))``, so prose and output cannot part
ways. This guard reads every markdown cell of every notebook (the jupytext ``.py`` files), takes
each number that carries a unit, a per cent sign, a × or x-ratio, or a degree sign, and fails
unless the number is

- the paper's own figure: the sentence says so ("the paper reports", "[Yuan]", "Table 2") and
  the number appears in the text of the papers (``../shared/seeds``; the check skips with its
  reason when the texts are absent), or
- a definitional constant of that notebook: a chosen parameter, listed in :data:`CONSTANTS`
  with the reason it may be typed.

A second check reads the asserts of every code cell: one that compares with a literal factor of
three or more (``x < 3 * y``, ``x > y / 4``) must say why, in its message or in a comment on its
line or the line above, since an assert with an empty margin cannot fail.

Each offending number is reported with its notebook and line.
"""

from __future__ import annotations

import ast
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
#: The papers' texts beside the repository (``../shared/seeds``), or one level further out when
#: the repository is checked out in a subfolder of the work area.
SEEDS = next(
    (d for d in (ROOT.parent / "shared" / "seeds", ROOT.parents[1] / "shared" / "seeds") if d.is_dir()),
    ROOT.parent / "shared" / "seeds",
)

#: Units a number may carry. Longer spellings first so the alternation takes the whole word.
UNITS = (
    r"per\s?cent|percent|%|°/s|°|×|"
    r"km/h|m/s²|m/s|rad/s|mrad|rad|deg(?:rees?)?|"
    r"km|cm|mm|µm|m|metres?|meters?|centimetres?|millimetres?|"
    r"ms|µs|s|seconds?|milliseconds?|minutes?|min|"
    r"px|pixels?|Hz|kHz|fps|bits?|MB|GB|kB|x"
)
_NUM = r"\d+(?:[.,]\d+)*(?:\s?[eE][−-]?\d+)?"
#: A number (or a range of two) and its unit; the unit must end at a word boundary, so "3 months"
#: or "2D" are not read as metres or a ratio.
NUMBER_WITH_UNIT = re.compile(
    rf"(?<![\w.^_/])(?P<num>[~≈<>≤≥±−-]?\s?{_NUM}(?:\s?[–-]\s?{_NUM})?)"
    rf"\s?(?:\\,|\\ )?(?P<unit>{UNITS})(?![\w²³/])(?!\s+of\s+freedom)"
)
#: A ratio written with the sign first: "×5", "x 10".
RATIO_FIRST = re.compile(rf"(?<![\w\d])[×](?P<num>\s?{_NUM})(?![\w×])")
#: A magnitude in scientific notation ("~1e-14", "10⁻¹²") states a measured size even without a unit.
SCIENTIFIC = re.compile(
    r"(?<![\w.])(?P<num>[~≈<>≤≥]?\s?(?:\d+(?:\.\d+)?[eE][−-]?\d+|(?:\d+(?:\.\d+)?\s?[·×]\s?)?10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+))(?!\w)"
)
#: Grid sizes such as 4×4 or 3×3 panels are dimensions, not ratios.
DIMENSION = re.compile(rf"{_NUM}\s?×\s?(?:{_NUM}|[a-zA-Z]\b)")
#: Words by which a sentence says it quotes a paper.
CITES_PAPER = re.compile(
    r"paper|\[(?:Zhao|Yan 2020|Yuan)\]|Table\s+\d|Fig(?:ure|\.)\s*\d|authors|\bMonteiro|Zhao|Sun\b", re.I
)

#: The header's run time is the whole notebook's wall time, which no cell can compute before the
#: notebook ends; it is an estimate for the reference machine, not a result.
RUN_TIME = re.compile(r"\s*\*\*Run time\*\*")

#: Definitional constants typed in a notebook's prose: chosen parameters of the experiments, the
#: robot's nominal geometry, conventional thresholds. Keyed by notebook stem, then by the number
#: as written (with its unit), each with the reason it may be typed.
CONSTANTS: dict[str, dict[str, str]] = {
    "02_circular_motion_derivation": {
        "5 cm": "the tolerance the exercise sets",
        "0.3 m": "the camera offset the stretch goal prescribes",
    },
    "03_circular_motion_numeric_checks": {
        "1e-6": "the tolerance exercise 3's tests check to",
        "±20 °": "the range of the random turns drawn in section 1",
        "±0.5 m": "the range of the random chords drawn in section 1",
        "1.5–15 m": "the depth range of the synthetic matches",
        "0.5 px": "the pixel noise chosen for the experiments",
        "12 cm": "the baseline of the simulated Bumblebee2-like rig",
        "15 m": "the far end of the chosen depth range",
        "8 cm": "the chord of the chosen test motion",
        "±300 px": "a widget setting suggested to the reader",
        "3 °": "the turn the exercise prescribes",
        "2 °": "the turn the exercise prescribes",
        "0.3 m": "the camera offset the exercise prescribes",
        "10 °": "the tilt the stretch goal prescribes",
        "2–5 °": "the range of peak tilt the simulated ground gives a loss of contact (TrackGround.tilt_deg)",
    },
    "07_kalman_fusion": {
        "1e-12": "the tolerance the comparison is held to",
        "1 %": "the slip per metre the filter's process noise assumes (SLIP_SIGMA)",
        "18 °/s": "the turn rate of the simulated spot-turn drive",
        "6 %": "the mean slip the simulated spot turn is given",
        "0.5 px": "the pixel noise chosen for the synthetic matches",
        "2 px": "the pixel noise chosen for the weak-vision condition of section 4",
        "30 %": "the outlier share chosen for the synthetic matches",
        "2 mm": "the sideways pseudo-measurement's σ, a chosen constant (SIDEWAYS_SIGMA)",
        "95 %": "the confidence level of the χ² band, by choice",
        "2.0 m": "a number the exercise sets",
        "2.6 m": "a number the exercise sets",
    },
    "09_line_feature_ekf_slam": {
        "0.05 m": "the range noise exercise 3 gives for its candidates",
        "0.02 rad": "the bearing noise exercise 3 gives for its candidates",
        "360 °": "the field of view given to the scanner of the check",
        "30 m": "the laser range of the paper's simulation, given to the scanner of the check",
        "99 %": "the confidence level of the association gate, by choice",
        "5 °": "the heading doubt chosen for the association example",
        "20 m": "the distance of the walls in the association example",
        "4 °": "the bearing offset chosen for the association example",
        "0.9 m": "the extra distance chosen for wall B in the example",
        "1e-12": "the tolerance the comparison is held to",
        "0.1 m": "the paper's range noise, repeated in the example",
        "1 cm": "the observers' default tolerance (DEFAULT_TOLERANCE)",
        "10 m": "a segment length in a worked conversion of the tolerance",
        "2 °": "the direction-σ limit chosen for the line observation",
        "95 %": "the confidence level of the χ² band, by choice",
        "~100 m": "the distance the stretch goal moves the walls to",
    },
    "10_vo_assisted_lidar_tracking": {
        "0 °": "the start of the interval an axis direction is folded into, by definition",
        "180 °": "the end of that interval: a direction and its opposite are one axis",
        "30 m": "the length of the simulated corridor",
        "3 m": "the width of the simulated corridor",
        "270 °": "the field of view of the simulated SICK TIM551",
        "10 m": "the range of the simulated SICK TIM551",
        "10 cm": "the likelihood field's σ and the along-heading spread of the samples, both chosen",
        "15 px": "the matching radius chosen for the motion-model matching",
        "45 °": "the viewing-angle limit chosen for our reading of eq. 7",
        "3 cm": "the across-heading spread chosen for the samples",
        "0.5 °": "the heading spread chosen for the samples",
    },
    "11_real_stereo_data": {
        "1e-12": "the convergence tolerance the exercise sets",
        "±2 px": "the disparity search window chosen around an upper level's corner",
        "1 px": "the threshold of the histogram's tail and of the Huber weights, both chosen",
        "2 px": "the disparity change chosen to call a patch a depth edge",
        "0.1 °": "the pitch the exercise prescribes",
        "20 m": "the distance the exercise prescribes",
        "1e-10": "the tolerance the exercise's hint passes",
    },
    "12_real_drive_pipeline": {
        "90 °": "a right-angle turn at a crossing, by definition",
        "3–5 °": "90° in two or three seconds at 10 Hz, worked in the sentence itself",
        "10 Hz": "KITTI's frame rate",
        "0.5 px": "the pixel noise chosen for the synthetic matches",
        "20 %": "the outlier share chosen for the synthetic matches",
        "1 m": "the chord per frame chosen for the synthetic turns",
        "1 px": "the refinement's inlier threshold, chosen",
        "5 °": "the turn the exercise prescribes",
    },
    "04_world_and_sequences": {
        "66 °": "the horizontal field of view chosen for the simulated camera",
        "0.5 m": "the height the simulated camera is mounted at",
        "270 °": "the field of view of the simulated scanner, as the paper's SICK TIM551",
        "0.25 px": "the disparity error the exercise prescribes",
        "2 m": "a wall distance the exercise prescribes",
        "10 m": "the scanner's range, and a wall distance the exercise prescribes",
        "0.3 m": "the scanner offset the exercise prescribes",
        "15 m": "a wall distance the stretch goal prescribes",
    },
    "05_stereo_front_end": {
        "16 pixels": "the FAST test circle, by definition of the detector",
        "64 px": "the disparity search range chosen for the matcher",
        "0.1 °": "the heading error given to the prediction on purpose",
        "5 mm": "the chord error given to the prediction on purpose",
        "1 °": "the pitch chosen to show the epipolar lines of a rig that is not rectified",
        "0.5 px": "the disparity noise σ_d chosen for the Monte Carlo (SIGMA_D)",
    },
    "06_one_point_ransac": {
        "3 °": "the turn of the synthetic matches, chosen (also the exercises' turn)",
        "8 cm": "the chord of the synthetic matches of section 1, chosen",
        "0.5 px": "the pixel noise chosen for the synthetic matches (and the gates' pixel_sigma)",
        "1 px": "the second pixel noise the exercises draw their matches with",
        "1.5–15 m": "the depth range of the synthetic matches",
        "40 %": "the outlier share chosen for the matches of section 1",
        "30 %": "the outlier share the exercises draw their matches with",
        "60 %": "the inlier share the chosen outlier shares leave (1 − 0.10 − 0.15 − 0.15)",
        "80 %": "the outlier share chosen for the adaptive-N_h test, the exercise and the stretch goal",
        "10 %": "the share of moving inliers the stretch goal prescribes",
        "2–8 px": "the range of the near misses' shift, chosen (NEAR_MISS_PX)",
        "6 px": "the moving object's shift between the frames, chosen (MOVER_PX)",
        "0.05 °": "the distance from the truth at which a hypothesis is called good (GOOD_HYPOTHESIS), "
        "and ransac_trial's θ tolerance",
        "5 %": "ransac_trial's ρ tolerance, chosen",
        "99.73 %": "the confidence level of the whitened eq. 21 gate (three sigma's share), by choice",
        "99.9 %": "the confidence level the hypothesis count is computed for, by choice",
        "0.01 °": "the first threshold of the grid the exercise searches",
        "0.02 °": "the second threshold of the grid the exercise searches",
        "8.00 °": "the end of the threshold grid the exercise sets",
    },
    "08_full_pipeline": {
        "95 %": "the confidence level of the χ² band, by choice",
        "6 %": "the mean slip the simulated drives are given in spot turns",
        "1.5 °": "the turn of the synthetic keyframe step, chosen (key_theta)",
        "4 cm": "the chord of the synthetic keyframe step, chosen (key_rho)",
        "1 cm": "the step length the exercises' drive is built from (ex_step_length)",
        "0.01 °": "the heading drift per step the exercises' estimate is given (ex_drift)",
        "1 %": "the tolerance the exercise sets",
        "0.3 m": "the camera offset the stretch goal prescribes",
    },
    "01_crawler_odometry": {
        "1 cm": "the encoder noise chosen for the model, σ per square-root metre; also the exercise's step",
        "360 °": "one full turn, by definition",
        "10 %": "the slip the exercise prescribes",
        "1,080 °": "three full turns, the recorded spot turns of the exercise",
        "0.60 m": "the nominal gauge of the odometry model the exercise starts from",
        "0.1 °": "the tolerance the exercise sets",
    },
}


def _markdown_lines(path: pathlib.Path):
    """Yield (line number, text) for every line of every markdown cell of a jupytext file."""
    in_markdown = False
    in_fence = False
    for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if line.startswith("# %%"):
            in_markdown = "[markdown]" in line
            in_fence = False
            continue
        if not in_markdown:
            continue
        text = line[2:] if line.startswith("# ") else line.lstrip("#")
        if text.lstrip().startswith("```"):
            in_fence = not in_fence
            continue
        if not in_fence and not RUN_TIME.match(text):
            yield n, text


def _seed_text() -> str:
    return "\n".join(p.read_text(encoding="utf-8", errors="replace") for p in SEEDS.glob("*.txt"))


def _normalise(number: str) -> str:
    return re.sub(r"\s", "", number.replace("−", "-"))


def _bare(number: str) -> list[str]:
    """The plain numerals of a match: "~10–20" gives ["10", "20"]."""
    return re.findall(r"\d+(?:[.,]\d+)*(?:[eE]-?\d+)?", _normalise(number))


def _paragraphs(path: pathlib.Path):
    """The markdown prose as paragraphs: lists of (line number, text) of consecutive lines."""
    paragraph: list[tuple[int, str]] = []
    for n, text in _markdown_lines(path):
        if paragraph and (n != paragraph[-1][0] + 1 or not text.strip()):
            yield paragraph
            paragraph = []
        if text.strip():
            paragraph.append((n, text))
    if paragraph:
        yield paragraph


def _blank(m: re.Match) -> str:
    return " " * len(m.group())  # keeps every offset in place


def numbers_in_prose(path: pathlib.Path):
    """Yield (line, written form, sentence) for every unit-bearing number of the markdown cells.

    The sentence is the one the number stands in, read across line breaks, so that a figure on
    the line after "the paper reports" is still the paper's.
    """
    for paragraph in _paragraphs(path):
        joined, starts = "", []
        for _, text in paragraph:
            starts.append(len(joined))
            joined += text + " "
        ends = [m.end() for m in re.finditer(r"[.!?;:](?=\s+[A-Z(*•-])", joined)] + [len(joined)]
        for (n, text), start in zip(paragraph, starts, strict=True):
            clean = re.sub(r"\]\([^)]*\)", _blank, text)  # link targets are addresses, not prose
            clean = DIMENSION.sub(_blank, clean)
            found = [
                (m.start(), f"{_normalise(m['num'])} {m['unit']}".strip())
                for m in NUMBER_WITH_UNIT.finditer(clean)
            ]
            found += [(m.start(), f"×{_normalise(m['num'])}") for m in RATIO_FIRST.finditer(clean)]
            found += [(m.start(), _normalise(m["num"])) for m in SCIENTIFIC.finditer(clean)]
            for offset, form in sorted(found):
                at = start + offset
                end = next(e for e in ends if e > at)
                begin = max([e for e in ends if e <= at], default=0)
                yield n, form, joined[begin:end].strip()


def _in_papers(numeral: str, seeds: str) -> bool:
    """The numeral is in the papers' text as printed, or as a rounding of a printed decimal.

    "26.55" stands for the printed 26.5511; a whole number must be printed as it is, since any
    number rounds to some whole number.
    """
    if re.search(rf"(?<![\d.]){re.escape(numeral)}(?![\d])", seeds):
        return True
    if "." not in numeral:
        return False
    decimals = len(numeral.split(".")[1])
    value = float(numeral)
    if seeds not in _SEED_DECIMALS:
        _SEED_DECIMALS[seeds] = re.findall(r"(?<![\d.])\d+\.\d+", seeds)
    return any(
        len(x.split(".")[1]) > decimals and round(float(x), decimals) == value
        for x in _SEED_DECIMALS.get(seeds, ())
    )


_SEED_DECIMALS: dict[str, list[str]] = {}


def offending_numbers(path: pathlib.Path, seeds: str) -> list[str]:
    """Every number of ``path``'s prose without an accepted source, as "file:line: form | text"."""
    allowed = CONSTANTS.get(path.stem, {})
    allowed_forms = {_normalise(k) for k in allowed}
    bad = []
    for line, form, text in numbers_in_prose(path):
        if _normalise(form) in allowed_forms:
            continue
        if CITES_PAPER.search(text) and all(_in_papers(b, seeds) for b in _bare(form)):
            continue
        bad.append(f"{path.name}:{line}: {form!r} | {text.strip()}")
    return bad


def test_the_guard_reads_numbers():
    """The extraction finds what a reader sees as a figure, and leaves what is not one."""
    found = [f for _, f, _ in _numbers_of("The wall is 9.6 m ahead, 38.8 % empty, ~10–20 bits, 4.9×.")]
    assert found == ["9.6 m", "38.8 %", "~10–20 bits", "4.9 ×"]
    none = (
        "Five 4×4 panels, a 2 × n matrix, eq. 14, §6, 2D, 3 cameras, x_k, χ² with 3 degrees of "
        "freedom, π/9 rad/s."
    )
    assert [f for _, f, _ in _numbers_of(none)] == []
    assert [f for _, f, _ in _numbers_of("a heading of 2° and ×5 faster")] == ["2 °", "×5"]
    assert [f for _, f, _ in _numbers_of("θ and ρ to ~1e-14, or 10⁻¹²")] == ["~1e-14", "10⁻¹²"]
    assert _in_papers("26.55", "a mean of 26.5511 ms") and not _in_papers("26.56", "26.5511 ms")
    assert not _in_papers("27", "26.5511 ms")


def _numbers_of(sentence: str):
    tmp = pathlib.Path(__file__).with_name("_prose_probe.py")
    try:
        tmp.write_text(f"# %% [markdown]\n# {sentence}\n", encoding="utf-8")
        return list(numbers_in_prose(tmp))
    finally:
        tmp.unlink(missing_ok=True)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_prose_numbers_have_a_source(path):
    if not SEEDS.is_dir():
        pytest.skip(f"the papers' texts ({SEEDS}) are absent: the paper's figures cannot be checked")
    bad = offending_numbers(path, _seed_text())
    assert not bad, (
        f"{len(bad)} number(s) in the prose of {path.name} have no source; write them from a code "
        "cell with display(Markdown(f'...')), cite the paper, or list a constant:\n" + "\n".join(bad)
    )


def test_constants_are_used_and_explained():
    """Each listed constant is typed in its notebook and carries a reason."""
    for stem, table in CONSTANTS.items():
        path = ROOT / "notebooks" / f"{stem}.py"
        assert path.is_file(), f"CONSTANTS names a notebook that does not exist: {stem}"
        forms = {_normalise(f) for _, f, _ in numbers_in_prose(path)}
        for form, reason in table.items():
            assert len(reason.split()) >= 3, f"{stem}: {form!r} needs a reason"
            assert _normalise(form) in forms, f"{stem}: {form!r} is listed but not in the prose"


# --- asserts with an empty margin ------------------------------------------------------------

_FACTOR = 3.0


def _literal_factor(node: ast.AST) -> float | None:
    """The literal factor by which a side of a comparison is scaled (``3 * x``, ``x / 4``)."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        for side in (node.left, node.right):
            if isinstance(side, ast.Constant) and isinstance(side.value, (int, float)):
                return float(side.value)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
        if isinstance(node.right, ast.Constant) and isinstance(node.right.value, (int, float)):
            return 1.0 / float(node.right.value) if node.right.value else None
    return None


def wide_margins(path: pathlib.Path) -> list[str]:
    """Asserts whose bound is a literal multiple (≥ 3× or ≤ 1/3) of the other side, uncommented."""
    source = path.read_text(encoding="utf-8")
    lines = source.splitlines()
    bad = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Assert) or not isinstance(node.test, ast.Compare):
            continue
        cmp = node.test
        if len(cmp.ops) != 1:
            continue
        op, left, right = cmp.ops[0], cmp.left, cmp.comparators[0]
        if isinstance(op, (ast.Lt, ast.LtE)):
            factor, other = _literal_factor(right), _literal_factor(left)
        elif isinstance(op, (ast.Gt, ast.GtE)):
            factor, other = _literal_factor(left), _literal_factor(right)
        else:
            continue
        loose = (factor is not None and factor >= _FACTOR) or (other is not None and 0 < other <= 1 / _FACTOR)
        said = (
            node.msg is not None
            or "#" in lines[node.lineno - 1]
            or lines[node.lineno - 2].lstrip().startswith("#")
        )
        if loose and not said:
            bad.append(f"{path.name}:{node.lineno}: {lines[node.lineno - 1].strip()}")
    return bad


#: The notebooks and the checks of their claims (tests/notebook_checks), which run in their kernels.
ASSERTING = NOTEBOOKS + sorted((ROOT / "tests" / "notebook_checks").glob("*.py"))


@pytest.mark.parametrize("path", ASSERTING, ids=[f"{p.parent.name}/{p.stem}" for p in ASSERTING])
def test_wide_assert_margins_say_why(path):
    bad = wide_margins(path)
    assert not bad, "asserts with a margin of 3× or more and no comment saying why:\n" + "\n".join(bad)


# --- comparative sentences rest on seeds, not on one draw ------------------------------------

#: Notebooks whose comparisons are about random outcomes (draws of noise, slip, matches).
RANDOM_COMPARISONS = ("03", "06", "07", "08", "09", "10", "11", "12")
#: Words by which a sentence says one method or condition did better or worse than another.
COMPARATIVE = re.compile(
    r"\b(better|worse|helps?|helped|hurts?|beats?|beaten|outperforms?|outperformed|"
    r"more accurate|less accurate|(?:suffers?|errs?|gains?|loses?|costs?) (?:most|least)|"
    r"(?:most|least) (?:in|on|where|when|accurate))\b",
    re.I,
)
#: What a comparative sentence about a random outcome must carry: its seed count or share, or the
#: statement that the difference is not reliable.
SEED_FIGURE = re.compile(
    r"(?:\d+|\{[^{}]+\})\s+of\s+(?:\d+|\{[^{}]+\})\s+(?:seeds|runs|laps|draws)|"
    r"over\s+(?:\d+|\{[^{}]+\}|the)\s+(?:seeds|runs|laps|draws)|"
    r"not reliabl[ey]",
    re.I,
)
#: Sentences with a comparative word that are not claims about a random outcome, each with its
#: reason; keyed by notebook stem and a fragment of the sentence.
NOT_RANDOM: dict[str, dict[str, str]] = {
    "07_kalman_fusion": {
        "does fusion ever help?)": "announces the questions the seed figures below answer",
        "Above 3 the filter is over-confident": "defines what NEES values mean, no comparison of draws",
        "Fusion therefore helps where the two errors are independent noise": "the mechanism, stated "
        "ahead of the seed figures of the cell before it",
        "where fusion helps, where it hurts, and why": "the learning goals announce section 4's seed figures",
    },
}


NOT_RANDOM["10_vo_assisted_lidar_tracking"] = {
    "judge a tracker's output once the score is read": "describes section 3's one run and says so; the "
    "reading kept is a reading of the paper, which the run does not decide",
}


NOT_RANDOM["08_full_pipeline"] = {
    "Notebook 07 measures over seeds when fusing helps": "points to the seed comparisons of notebook 07",
}


def _story_cells(path: pathlib.Path) -> str:
    """The notebook's source up to its graded exercises (their text is set by the exercises)."""
    text = path.read_text(encoding="utf-8")
    cut = text.find("\n# ## Exercises")
    return text if cut < 0 else text[:cut]


def _sentences(text: str):
    """Sentences and list items; a question claims nothing and is left out."""
    parts = re.split(r"(?<=[.!?])\s+(?=[A-Z*(])|\s+(?=[-*] )", text)
    return [s.strip() for s in parts if s.strip() and not s.strip().endswith("?")]


def _markdown_sentences(path: pathlib.Path):
    """(line, sentence) of the markdown cells of the story."""
    story_lines = _story_cells(path).count("\n") + 1
    for paragraph in _paragraphs(path):
        if paragraph[0][0] > story_lines:
            break
        joined = " ".join(text.strip() for _, text in paragraph)
        for sentence in _sentences(joined):
            yield paragraph[0][0], sentence


def _literal_text(node: ast.AST) -> str:
    """The text a string expression writes, its computed parts as "{…}"."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(_literal_text(v) if isinstance(v, ast.Constant) else "{…}" for v in node.values)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        return _literal_text(node.left) + _literal_text(node.right)
    return "{…}"


def _imported_sentence_helpers(tree: ast.Module) -> set[str]:
    """Names the story imports from the project's own modules (a notebook's helper module) whose
    function calls ``Comparison.sentence``: a sentence they write rests on seeds."""
    names = set()
    for node in ast.walk(tree):
        if not (isinstance(node, ast.ImportFrom) and (node.module or "").startswith("vo_lib.")):
            continue
        module = ROOT / (node.module.replace(".", "/") + ".py")
        if not module.is_file():
            continue
        text = module.read_text(encoding="utf-8")
        defined = {
            f.name: ast.get_source_segment(text, f) or ""
            for f in ast.parse(text).body
            if isinstance(f, ast.FunctionDef)
        }
        names |= {a.asname or a.name for a in node.names if ".sentence(" in defined.get(a.name, "")}
    return names


def _code_sentences(path: pathlib.Path):
    """(line, literal text, written by a comparison) of every ``Markdown(...)`` the story's code
    writes: its string parts, and whether it calls ``Comparison.sentence`` (directly or through a
    function of the notebook that does)."""
    source = _story_cells(path)
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return
    helpers = {
        node.name
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef) and ".sentence(" in (ast.get_source_segment(source, node) or "")
    }
    helpers |= _imported_sentence_helpers(tree)
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Call) and getattr(node.func, "id", "") == "Markdown"):
            continue
        segment = ast.get_source_segment(source, node) or ""
        compared = ".sentence(" in segment or any(re.search(rf"\b{h}\(", segment) for h in helpers)
        parts = [_literal_text(arg) for arg in node.args]
        yield node.lineno, "".join(parts), compared


def unseeded_comparisons(path: pathlib.Path) -> list[str]:
    """Comparative sentences of ``path``'s story with no seed figure, as "file:line: sentence"."""
    allowed = NOT_RANDOM.get(path.stem, {})
    bad = []

    def check(line, sentence, compared=False):
        if not COMPARATIVE.search(sentence) or compared or SEED_FIGURE.search(sentence):
            return
        flat = " ".join(sentence.split())
        if any(" ".join(k.split()) in flat for k in allowed):
            return
        bad.append(f"{path.name}:{line}: {flat[:160]}")

    for line, sentence in _markdown_sentences(path):
        check(line, sentence)
    for line, text, compared in _code_sentences(path):
        for sentence in _sentences(text):
            check(line, sentence, compared)
    return bad


def test_the_comparison_guard_reads_sentences():
    """A comparative sentence passes with a seed share, or as a Comparison's sentence; a sentence
    without a comparative word, or with "at least", is not one."""
    assert COMPARATIVE.search("the fused filter does better") and not COMPARATIVE.search("at least 10")
    assert SEED_FIGURE.search("lower in 17 of 20 seeds") and SEED_FIGURE.search("in {n} of {m} seeds")
    assert SEED_FIGURE.search("the two are not reliably different") and not SEED_FIGURE.search("in one run")
    tmp = pathlib.Path(__file__).with_name("_comparison_probe.py")
    try:
        tmp.write_text(
            "# %% [markdown]\n# Fused beats VO. Fused beats VO in 9 of 10 seeds. The wall is grey.\n\n"
            "# %%\nc = None\ndisplay(Markdown('VO is worse.'))\ndisplay(Markdown(c.sentence('a', 'b')))\n",
            encoding="utf-8",
        )
        found = unseeded_comparisons(tmp)
    finally:
        tmp.unlink(missing_ok=True)
    assert [f.split(": ", 1)[1] for f in found] == ["Fused beats VO.", "VO is worse."]


def test_not_random_entries_are_used_and_explained():
    for stem, table in NOT_RANDOM.items():
        path = ROOT / "notebooks" / f"{stem}.py"
        said = [s for _, s in _markdown_sentences(path)] + [t for _, t, _ in _code_sentences(path)]
        text = " ".join(" ".join(said).split())
        for fragment, reason in table.items():
            assert len(reason.split()) >= 3, f"{stem}: {fragment!r} needs a reason"
            assert " ".join(fragment.split()) in text, f"{stem}: {fragment!r} is listed but not in its story"


_RANDOM_NOTEBOOKS = [p for p in NOTEBOOKS if p.stem[:2] in RANDOM_COMPARISONS]


@pytest.mark.parametrize("path", _RANDOM_NOTEBOOKS, ids=[p.stem for p in _RANDOM_NOTEBOOKS])
def test_comparisons_rest_on_seeds(path):
    bad = unseeded_comparisons(path)
    assert not bad, (
        f"{len(bad)} comparative sentence(s) of {path.name} state no seed count or share: write them "
        "with vo_lib.comparison (Comparison.sentence), state 'in k of n seeds', say the difference is "
        "not reliable, or list a statement that is not about a random outcome in NOT_RANDOM:\n"
        + "\n".join(bad)
    )
