"""``python -m vo_lib COMMAND``: run, evaluate, convert, generate, bench, sweep.

Bad input prints one line on stderr and exits with 2; SIGINT or SIGTERM removes what was
half-written, prints one line and exits with 130 or 143. Output folders follow :mod:`vo_lib.outputs`.
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import errno
import functools
import importlib
import os
import signal
import sys
import textwrap
import warnings
from pathlib import Path

from vo_lib.arguments import OneLineParser, UsageError, count_at_least, non_empty, one_line

#: Bounds of ``generate --resolution`` (each side, pixels): a few FAST corners, a few hundred MB.
MIN_SIDE, MAX_SIDE = 32, 4096


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 640x480; got {text!r}") from None
    if not (MIN_SIDE <= w <= MAX_SIDE and MIN_SIDE <= h <= MAX_SIDE):
        raise argparse.ArgumentTypeError(f"each side must lie in {MIN_SIDE}..{MAX_SIDE} pixels; got {text!r}")
    return w, h


def _segments(text: str) -> tuple[float, ...]:
    try:
        lengths = tuple(float(x) for x in text.split(","))
    except ValueError:
        lengths = ()
    if not lengths or not all(1e-3 <= x <= 1e6 for x in lengths):  # a millimetre to 1,000 km
        raise argparse.ArgumentTypeError(
            f"expected comma-separated lengths in metres, each 0.001 to 1e+06, e.g. 1,2,5; got {text!r}"
        )
    return tuple(sorted(set(lengths)))  # each length once, shortest first


def _recording(text: str) -> str:
    from vo_lib.formats.euroc import mav0_of

    if mav0_of(text) is None:
        raise argparse.ArgumentTypeError(
            f"expected an ASL recording (a folder holding mav0/cam0, or mav0 itself); got {text!r}"
        )
    return text


def _no_truth(parser: argparse.ArgumentParser, what: str) -> None:
    why = f"read no ground truth (one that does not cover every image stops the {what})"
    parser.add_argument("--no-truth", action="store_true", help=why)


def build_parser() -> argparse.ArgumentParser:
    from vo_lib.bench import BENCH_HELP, BENCHES
    from vo_lib.cli.sweep import SWEEPS
    from vo_lib.sim.samples import SAMPLES

    prog = "vo-lib" if Path(sys.argv[0]).name == "vo-lib" else "python -m vo_lib"

    def example(*lines: str) -> str:
        return "example" + ("s" if len(lines) > 1 else "") + ":\n" + "\n".join(f"  {prog} {x}" for x in lines)

    # descriptions are wrapped here, examples kept as written
    plain = functools.partial(OneLineParser, formatter_class=argparse.RawDescriptionHelpFormatter)

    def output(p, what: str, **kwargs) -> None:
        p.add_argument("--out", type=non_empty("a folder"), help=f"output folder ({what})", **kwargs)
        force = "replace --out where another command of this program wrote it, as it wrote it"
        p.add_argument("--force", action="store_true", help=force)

    parser = plain(
        prog=prog,
        description=textwrap.fill(
            "Stereo visual odometry for a crawler robot [Zhao], line-feature EKF-SLAM [Yan 2020] and "
            "VO-assisted laser pose tracking [Yuan], run from the command line. Each command has its own "
            "--help.",
            88,
        ),
        epilog=example(
            "run                          # the default sample, indoor_linear",
            "run --sequence corridor --no-odometry",
            "evaluate --gt data/indoor_linear/poses.txt --est runs/indoor_linear/poses.txt",
            "convert /data/MH_01_easy --to kitti --out /tmp/mh01",
            "generate outdoor_free --frames 200",
            "bench ransac",
            "sweep corridor --seeds 200 --workers 2",
        )
        + "\n\nBad input prints one line and exits with status 2; Ctrl-C exits with 130.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=plain)

    def command(name: str, help: str, description: str, *examples: str, listing: str = ""):
        description = textwrap.fill(description, 88) + listing
        return sub.add_parser(name, help=help, description=description, epilog=example(*examples))

    run = command(
        "run",
        "run the stereo visual odometry pipeline on a sample, a KITTI-layout folder, a raw KITTI drive "
        "or an ASL recording",
        "Run [Zhao]'s stereo visual odometry on a sequence and print a timing table and, "
        "where the sequence has ground truth, its errors. A named sample is rendered into data/ on "
        "first use (seconds to a minute: the run's first line says) and reused after. Writes into "
        "--out (default runs/NAME, runs/NAME_Nf with --frames N): "
        "poses.txt (KITTI), trajectory.tum (TUM), timings.csv, diagnostics.csv and trajectory.png.",
        "run --sequence outdoor_free --out runs/yard",
    )
    run.add_argument(
        "--sequence",
        type=non_empty("a sample name or a folder"),
        help="sample name, KITTI-layout folder, raw KITTI drive (as stored) or ASL recording (default: "
        "indoor_linear)",
    )
    output(run, "default: runs/NAME, or runs/NAME_Nf with --frames N; new, empty, or written by a run")
    run.add_argument("--frames", type=count_at_least(2, "frames"), help="process only the first N frames")
    run.add_argument(
        "--no-odometry",
        action="store_true",
        help="ignore the odometry (odometry.txt, or a raw drive's OXTS): constant-velocity prediction",
    )
    _no_truth(run, "run")
    run.add_argument(
        "--seed", type=count_at_least(0, "seed"), default=0, help="seed of the RANSAC draws (>= 0)"
    )
    run.add_argument(
        "--motion",
        choices=("auto", "planar", "full", "hover"),
        default="auto",
        help="motion model: planar circular motion (the crawler), full 6-DoF (a car), hover (6-DoF, a"
        " drone or a hand-held rig), or auto (default: the one that fits the sequence's vehicle)",
    )
    ev = command(
        "evaluate",
        "ATE, RPE and KITTI segment errors of an estimate against ground truth",
        "Print the absolute trajectory error, the relative pose error and KITTI's segment "
        "errors of an estimated trajectory against ground truth (KITTI, TUM, EuRoC CSV or position "
        "files), associated by timestamp where both carry them, else pose by pose.",
        "evaluate --gt data/indoor_linear/poses.txt --est runs/indoor_linear/poses.txt --segments 1,2",
    )
    ev.add_argument(
        "--gt",
        required=True,
        type=non_empty("a ground-truth file"),
        help="ground truth: KITTI poses, TUM, EuRoC CSV, or positions (t x y z)",
    )
    ev.add_argument(
        "--est",
        required=True,
        type=non_empty("a pose file"),
        help="estimated poses (KITTI, TUM or EuRoC CSV)",
    )
    ev.add_argument(
        "--extrinsic-of",
        metavar="RECORDING",
        type=_recording,
        help="an ASL recording (holding mav0) whose calibration moves a body-frame --gt into its "
        "rectified left camera (positions: from its laser tracker's prism)",
    )
    ev.add_argument(
        "--est-frame",
        choices=("camera", "body"),
        default="camera",
        help="the frame --est's poses are of: the rectified left camera (default; what run writes), or "
        "the body of --gt's recording (a visual-inertial system's IMU), into which its truth is then moved",
    )
    ev.add_argument(
        "--segments",
        type=_segments,
        help="comma-separated segment lengths in metres (default: KITTI's 100..800)",
    )
    ev.add_argument(
        "--time-offset",
        metavar="SECONDS",
        type=float,
        default=argparse.SUPPRESS,
        help="added to --est's timestamps before they are paired with --gt's: the lag of a clock not "
        "synchronised with the cameras, as evo's --t_offset (default: 0)",
    )
    ev.add_argument(
        "--max-time-diff",
        metavar="SECONDS",
        type=float,
        default=argparse.SUPPRESS,
        help="largest difference of two paired timestamps, as evo's --t_max_diff (default: 0.01)",
    )
    conv = command(
        "convert",
        "write a KITTI-layout copy of a recording (ASL layout, rectified; or a raw KITTI drive)",
        "Undistort and rectify a recording in EuRoC's ASL layout (the folder holding mav0, or mav0) "
        "and write it in the KITTI odometry layout, with its ground truth in the rectified left camera "
        "(a drive of KITTI's raw set as stored, too: its OXTS packets and calibration carried).",
        "convert /data/MH_01_easy --to kitti --out /tmp/mh01",
    )
    conv.add_argument(
        "sequence",
        type=non_empty("a recording folder"),
        help="the recording (ASL layout) or any sequence folder",
    )
    conv.add_argument("--to", choices=("kitti",), default="kitti", help="layout to write (kitti)")
    _no_truth(conv, "copy")
    output(conv, "new, empty, or written by a convert", required=True)
    gen = command(
        "generate",
        "render a named sample sequence in the KITTI layout",
        "Render a named sample (stereo images, ground truth, odometry, manifest) into a "
        "folder in the KITTI odometry layout. Samples: " + ", ".join(sorted(SAMPLES)) + ".",
        "generate indoor_free --out /tmp/indoor_free --resolution 320x240",
    )
    gen.add_argument("name", choices=sorted(SAMPLES), help="which sample")
    output(gen, "default: data/NAME")
    gen.add_argument(
        "--frames",
        type=count_at_least(2, "frames"),
        help="keep only the first N frames (2 or more: a run needs two)",
    )
    gen.add_argument(
        "--resolution",
        type=_resolution,
        help=f"WIDTHxHEIGHT, each side {MIN_SIDE}..{MAX_SIDE} (default: the sample's own, 640x480; "
        "1242x375 for road_drive)",
    )
    width = max(map(len, BENCH_HELP))
    bench = command(
        "bench",
        "time one part of the library against its baseline",
        "Time one part of the library against its baseline and print the table. The benchmarks, "
        "with how long each runs on a 2-core machine:",
        "bench geometry",
        listing="\n\n"
        + "\n".join(
            textwrap.fill(
                f"{what} ({how})",
                100,
                initial_indent=f"  {name:<{width}}  ",
                subsequent_indent=" " * (width + 4),
            )
            for name, (what, how) in BENCH_HELP.items()
        ),
    )
    bench.add_argument("name", choices=sorted(BENCHES), metavar="NAME", help="which benchmark (listed above)")
    sweep = command(
        "sweep",
        "a paper's statistic over many seeds, serially or on Dask",
        "Run one experiment over many seeds, one task per seed, on a local Dask cluster (one "
        "worker per core) or on a running scheduler; write results.csv and print each figure's "
        "mean, spread and 95 % interval over the seeds.",
        "sweep lap --seeds 50 --workers 2",
    )
    sweep.add_argument("name", choices=sorted(SWEEPS), help="which experiment")
    sweep.add_argument(  # 100,000 tasks take hours on a cluster; more is a typo
        "--seeds", type=count_at_least(1, "seeds", 100_000), default=20, help="number of seeds (default 20)"
    )
    sweep.add_argument(
        "--workers",  # beyond 1,024 local processes is a typo (beyond four per core: refused by the sweep)
        type=count_at_least(1, "workers", 1024),
        help="local worker processes (default: one per core; 1 runs in this process)",
    )
    sweep.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://host:8786")
    output(sweep, "default: sweeps/NAME")
    return parser


class _Stopped(BaseException):
    """Raised by the SIGTERM handler (its argument the signal), so that ``finally`` blocks run."""


def _stop(signum, frame):
    """Ctrl-C or SIGTERM: raise it, remembered in ``outputs.INTERRUPTED`` where it may be dropped."""
    from vo_lib.outputs import INTERRUPTED

    INTERRUPTED.append(stop := KeyboardInterrupt() if signum == signal.SIGINT else _Stopped(signum))
    raise stop


def _signal_inside(exc: BaseException) -> BaseException | None:
    """Our interrupt or stop, if ``exc`` wraps one: a SystemError caused by it (a callback from
    compiled code), or an ImportError of a compiled module (the stop only remembered)."""
    from vo_lib.outputs import INTERRUPTED

    if isinstance(exc, ImportError) and INTERRUPTED:
        return INTERRUPTED[-1]
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, (KeyboardInterrupt, _Stopped)):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


STDOUT = "standard output"


class _Stdout:
    """``sys.stdout``, whose failures (a full disk under ``> file``) name it, not ``--out``."""

    def __init__(self, stream) -> None:
        self.stream = stream

    def __getattr__(self, name: str):
        value = getattr(self.stream, name)
        return functools.partial(self._named, value) if name in ("write", "flush") else value

    @staticmethod
    def _named(call, *args):
        try:
            return call(*args)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror, STDOUT) from None


def closed_folder(path) -> Path | None:
    """The first folder on ``path`` that refuses to be searched (so nothing in it can be read)."""
    path = Path(os.fsdecode(path))
    for inner in [*reversed(path.parents), path][1:]:
        try:
            os.stat(inner)
        except PermissionError:
            return inner.parent
        except OSError:
            return None
    return None


def _os_error(exc: OSError, out) -> str:
    """What went wrong, named by what the user gave (``--out`` for a temporary output folder's file)."""
    why = "no space left on device" if exc.errno == errno.ENOSPC else (exc.strerror or str(exc))
    if exc.errno == errno.EACCES and exc.filename and (folder := closed_folder(exc.filename)):
        return f"{folder}: cannot read ({why})"
    if exc.filename and ".vo_lib-" not in str(exc.filename):
        return f"{exc.filename}: {why}"
    if out:
        return f"--out {out}: {why}; nothing was written"
    return why


def _dispatch(args) -> None:
    """Call ``COMMAND_command`` of ``vo_lib.cli.COMMAND`` (or of ``run``), imported only now."""
    if args.command == "bench":
        from vo_lib.bench import BENCHES

        return BENCHES[args.name]()
    module = "run" if args.command in ("convert", "generate") else args.command
    kwargs = {k: v for k, v in vars(args).items() if k != "command"}
    return getattr(importlib.import_module(f"vo_lib.cli.{module}"), f"{args.command}_command")(**kwargs)


def _run_parsed(args, command: str) -> int:
    """Run the parsed command: 0, or a line on stderr and 2 for what the user can fix (141: closed pipe)."""
    from vo_lib.formats.poses import TrajectoryError
    from vo_lib.outputs import OutputError

    stdout, sys.stdout = sys.stdout, _Stdout(sys.stdout)
    try:
        _dispatch(args)
        sys.stdout.flush()  # what is still buffered fails here, if it fails, not at exit
    except BrokenPipeError:  # e.g. piped into `head`
        # stdout, then stderr (2>&1: the same pipe) at devnull: the flush at exit would fail (status 120)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        with contextlib.suppress(OSError):
            print(f"{command}: stopped: whatever read its output closed the pipe", file=sys.stderr)
            sys.stderr.flush()
        os.dup2(devnull, sys.stderr.fileno())
        return 128 + signal.SIGPIPE
    except (UsageError, OutputError, TrajectoryError, OSError) as exc:  # SequenceError too
        why = _os_error(exc, getattr(args, "out", None)) if isinstance(exc, OSError) else exc
        print(f"{command}: error: {one_line(why)}", file=sys.stderr)
        if isinstance(exc, OSError) and exc.filename == STDOUT:  # what it still holds goes nowhere
            with contextlib.suppress(OSError, ValueError):
                os.dup2(os.open(os.devnull, os.O_WRONLY), stdout.fileno())
        return 2
    finally:
        sys.stdout = stdout
    return 0


@contextlib.contextmanager
def _signals():
    """SIGTERM and SIGINT handled by :func:`_stop` meanwhile, unraisable ones kept quiet."""
    from vo_lib.atomic import signals_to
    from vo_lib.outputs import INTERRUPTED

    INTERRUPTED.clear()
    previous_hook = sys.unraisablehook
    sys.unraisablehook = lambda info: (
        isinstance(info.exc_value, (KeyboardInterrupt, _Stopped)) or previous_hook(info)
    )
    try:
        with signals_to(_stop):
            yield
    finally:
        sys.unraisablehook = previous_hook


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and run the command; returns the exit status (argparse exits with 2 itself)."""
    command = "python -m vo_lib"
    if sys.stdout is None:  # started with it closed (>&-): Python gives None, and results go nowhere
        print(f"{command}: error: {STDOUT} is closed; expected it open (e.g. >/dev/null)", file=sys.stderr)
        return 2
    with _signals(), warnings.catch_warnings():
        # Pillow's notes on an image it still decodes (an APNG chunk it passes over) are not errors
        warnings.filterwarnings("ignore", module=r"PIL\.")
        try:
            try:
                parser = build_parser()  # its imports too: a signal may land inside NumPy's
                args, extra = parser.parse_known_args(argv)
                if extra:  # said by the command's own parser, which names the command
                    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
                    commands.choices[args.command].error(f"unrecognized arguments: {' '.join(extra)}")
                command = f"{parser.prog} {args.command}"
                return _run_parsed(args, command)
            except (SystemError, ImportError) as exc:  # a signal inside compiled code, or a module it loads
                if (stop := _signal_inside(exc)) is None:
                    raise
                raise stop from None
        except (KeyboardInterrupt, _Stopped) as stop:
            signum = signal.Signals(stop.args[0]) if isinstance(stop, _Stopped) else signal.SIGINT
            how = "interrupted (Ctrl-C)" if signum == signal.SIGINT else f"stopped by {signum.name}"
            print(f"{command}: {how}; nothing half-written is left", file=sys.stderr)
            return 128 + signum


def _early_stop(signum, frame) -> None:
    """A signal while the command's modules load: one line, nothing to undo."""
    os.write(2, f"vo_lib: {signal.Signals(signum).name} while starting; nothing was done\n".encode())
    os._exit(128 + signum)


def _late_stop(signum, frame) -> None:
    """A signal once the command has finished, while the interpreter shuts down: one line."""
    with contextlib.suppress(OSError, ValueError):  # stdout or stderr closed by then
        sys.stdout.flush()
        os.write(
            2, f"vo_lib: {signal.Signals(signum).name} while exiting; the command had finished\n".encode()
        )
    os._exit(128 + signum)


@atexit.register  # registered on import, before any library's: it runs after all of theirs
def _ignore_signals_in_teardown() -> None:
    """Signals ignored after the last exit function: in the teardown Python runs no handler."""
    if signal.getsignal(signal.SIGINT) is _late_stop:  # a command that finished (see entry)
        for kind in (signal.SIGINT, signal.SIGTERM):
            signal.signal(kind, signal.SIG_IGN)


def entry() -> int:
    """The ``vo-lib`` script: :func:`_early_stop` until :func:`main` handles signals itself, then
    :func:`_late_stop` while the interpreter joins threads and runs exit functions (seconds for a
    Dask cluster). A command a signal stopped ends at once; a path not UTF-8 prints as its bytes."""
    for kind in (signal.SIGINT, signal.SIGTERM):
        signal.signal(kind, _early_stop)
    with contextlib.suppress(AttributeError, ValueError):  # a stream replaced by one without it
        sys.stdout.reconfigure(errors="surrogateescape")
    status = main()
    if status in (128 + signal.SIGINT, 128 + signal.SIGTERM):  # end here: a thread may be half-started
        with contextlib.suppress(OSError, ValueError):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(status)
    if status < 128:  # not stopped by a signal already
        for kind in (signal.SIGINT, signal.SIGTERM):
            signal.signal(kind, _late_stop)
    return status
