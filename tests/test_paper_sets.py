"""The stored results against the present code: the paper-length sets notebook 08 reads
(vo_lib/stereo_vo/paper_sets.json) and notebook 07's seed study (vo_book/demo_fusion.json).

The quick tests check that each stored file covers what its notebook reads, from the present
sample definitions; the ``samples``-marked tests run them again (minutes) and require the same
figures: same seed, same result. They run every paper-length set whole, and of each seed study
every fifth drive (:data:`CHECKED_EVERY`: the first, the sixth, ...; of the fusion study's forty,
every twentieth): each drive is computed on its own, so a change of the code that moves the study
moves those drives too, and a few of the drives keep CI inside its time.
``python -m vo_lib.stereo_vo.paper_sets fusion`` (and ``contradictions``, and
``python -m vo_book.demo_fusion``) still make the whole studies.
"""

import json

import pytest

from vo_book import demo_fusion
from vo_lib.sim.samples import SAMPLES, fingerprint
from vo_lib.stereo_vo import paper_sets

#: Of a seed study's drives, those run again: every fifth (of the fusion study's, every twentieth).
CHECKED_EVERY = 5
FUSION_CHECKED_EVERY = 20


def test_stored_results_cover_every_set_whole_from_the_present_samples():
    stored = paper_sets.load()  # raises when a sample changed since its set was run
    assert set(stored["sets"]) == set(paper_sets.SETS)
    for name, row in stored["sets"].items():
        assert row["frames"] == SAMPLES[name].frames, f"{name} stored shortened"
        assert row["fingerprint"] == fingerprint(name)
        assert len(row["code_version"]) >= 40 and not row["code_version"].endswith("+changes")
        assert row["keys"] == len(range(paper_sets.KEY_EVERY, row["frames"], paper_sets.KEY_EVERY))
        assert set(paper_sets.PAPER[name]) <= set(row["fused"])


def test_load_refuses_results_of_other_samples(tmp_path):
    stored = json.loads(paper_sets.RESULTS.read_text())
    stored["sets"]["spot_turn"]["fingerprint"] = "0" * 16
    path = tmp_path / "paper_sets.json"
    path.write_text(json.dumps(stored))
    with pytest.raises(ValueError, match="spot_turn"):
        paper_sets.load(path)


def test_unknown_set_is_one_clear_line(capsys):
    assert paper_sets.main(["no_such_set"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no_such_set" in err


@pytest.mark.samples
@pytest.mark.parametrize("name", paper_sets.SETS)
def test_stored_set_is_what_the_code_computes(name):
    stored = paper_sets.load()["sets"][name]
    fresh = paper_sets.run_set(name)
    for key in ("frames", "keys", "flagged"):
        assert fresh[key] == stored[key], key
    for key in ("distance_m", "turned_deg", "mean_abs_heading_deg", "max_abs_heading_deg"):
        assert fresh[key] == pytest.approx(stored[key], rel=1e-9, abs=1e-12), key
    for part in ("fused", "odometry"):
        for quantity, values in stored[part].items():
            assert fresh[part][quantity] == pytest.approx(values, rel=1e-9, abs=1e-9), (part, quantity)


def test_stored_contradiction_study_is_present_and_current():
    study = json.loads(paper_sets.RESULTS.read_text())["contradictions"]
    assert study["fingerprint"] == fingerprint(study["set"])
    assert len(study["seeds"]) == paper_sets.CONTRADICTION_DRIVES >= 10
    assert study["seeds"][0] == SAMPLES[study["set"]].seed  # the sample's own drive, then new ones
    for label in ("never", "believed"):
        assert len(study[label]["flagged"]) == len(study["seeds"]) == len(study[label]["heading_rms_deg"])


@pytest.mark.samples
def test_stored_contradiction_study_is_what_the_code_computes():
    stored = json.loads(paper_sets.RESULTS.read_text())["contradictions"]
    drives = range(0, paper_sets.CONTRADICTION_DRIVES, CHECKED_EVERY)
    fresh = paper_sets.contradiction_study(drives)
    assert fresh["seeds"] == [stored["seeds"][k] for k in drives]
    for label in ("never", "believed"):
        assert fresh[label]["flagged"] == [stored[label]["flagged"][k] for k in drives], label
        expected = pytest.approx([stored[label]["heading_rms_deg"][k] for k in drives], rel=1e-9)
        assert fresh[label]["heading_rms_deg"] == expected, label


def test_stored_study_of_fusion_on_rendered_drives_is_present_and_current():
    study = json.loads(paper_sets.RESULTS.read_text())["fusion"]
    assert study["frames"] == paper_sets.FUSION_FRAMES and list(study["sets"]) == list(paper_sets.FUSION_SETS)
    for name, rows in study["sets"].items():
        assert rows["fingerprint"] == fingerprint(name), name
        assert rows["seeds"] == [SAMPLES[name].seed + k for k in range(paper_sets.FUSION_DRIVES)]
        for estimate in paper_sets.FUSION_ESTIMATES:
            assert all(len(v) == paper_sets.FUSION_DRIVES for v in rows[estimate].values()), (name, estimate)
        assert rows["odometry"]["flagged"] == [0] * paper_sets.FUSION_DRIVES  # odometry flags nothing


@pytest.mark.samples
def test_stored_study_of_fusion_on_rendered_drives_is_what_the_code_computes():
    stored = json.loads(paper_sets.RESULTS.read_text())["fusion"]
    drives = range(0, paper_sets.FUSION_DRIVES, FUSION_CHECKED_EVERY)
    fresh = paper_sets.fusion_study(drives)
    for name, rows in stored["sets"].items():
        assert fresh["sets"][name]["seeds"] == [rows["seeds"][k] for k in drives], name
        for estimate in paper_sets.FUSION_ESTIMATES:
            ours = fresh["sets"][name][estimate]
            theirs = {key: [values[d] for d in drives] for key, values in rows[estimate].items()}
            assert ours["flagged"] == theirs["flagged"], (name, estimate)
            for key in ("final_m", "heading_rms_deg"):
                expected = pytest.approx(theirs[key], rel=1e-9, abs=1e-12)
                assert ours[key] == expected, (name, estimate, key)


def test_stored_fusion_study_covers_the_notebooks_seeds_from_the_present_samples():
    stored = json.loads(demo_fusion.STORED.read_text())
    seeds = list(range(demo_fusion.SEED, demo_fusion.SEED + demo_fusion.STUDY_SEEDS))
    assert stored["seeds"] == seeds and stored["fingerprint"] == demo_fusion.study_fingerprint()
    assert set(stored["conditions"]) == set(demo_fusion.CONDITIONS)
    for rows in (*stored["conditions"].values(), stored["sideways"]):
        assert list(rows) == [str(s) for s in seeds]
    assert demo_fusion.seed_figures(seeds) == stored  # read, not run


def test_fusion_study_runs_for_other_seeds_or_when_asked(monkeypatch):
    monkeypatch.setattr(demo_fusion, "run_study", lambda seeds: {"ran": list(seeds)})
    stored_seeds = json.loads(demo_fusion.STORED.read_text())["seeds"]
    assert demo_fusion.seed_figures(range(3, 13)) == {"ran": list(range(3, 13))}
    assert demo_fusion.seed_figures(stored_seeds, fresh=True) == {"ran": stored_seeds}


@pytest.mark.samples
def test_stored_fusion_study_is_what_the_code_computes():
    stored = json.loads(demo_fusion.STORED.read_text())
    seeds = stored["seeds"][::CHECKED_EVERY]
    fresh = json.loads(json.dumps(demo_fusion.run_study(seeds)))  # seeds as text, as stored
    assert fresh["fingerprint"] == stored["fingerprint"]
    kept = {  # the stored figures of those seeds
        "conditions": {c: {str(s): rows[str(s)] for s in seeds} for c, rows in stored["conditions"].items()},
        "sideways": {str(s): stored["sideways"][str(s)] for s in seeds},
    }
    for part, rows in kept.items():
        flat_fresh, flat_stored = _leaves(fresh[part]), _leaves(rows)
        assert list(flat_fresh) == list(flat_stored)
        for key, value in flat_stored.items():
            assert flat_fresh[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key


def _leaves(tree, prefix=()):
    """A nested dict's numbers by their key path."""
    if not isinstance(tree, dict):
        return {prefix: tree}
    return {k: v for key, sub in tree.items() for k, v in _leaves(sub, (*prefix, key)).items()}
