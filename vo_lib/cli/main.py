"""Command line of the collection: ``python -m vo_lib COMMAND``.

Commands
--------
run            the stereo VO pipeline on a sample or a KITTI-layout folder (default: indoor_linear)
evaluate       trajectory errors of an estimate against ground truth (KITTI or TUM files)
generate NAME  render a named sample sequence (KITTI layout, with ground truth and odometry)
bench NAME     time one part of the library against its baseline (``bench --help`` lists them)
"""

from __future__ import annotations

import argparse
import sys


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 640x480; got {text!r}") from None
    if w < 32 or h < 32:
        raise argparse.ArgumentTypeError(f"resolution must be at least 32x32; got {text!r}")
    return w, h


def build_parser() -> argparse.ArgumentParser:
    from vo_lib.cli.bench import BENCHES

    parser = argparse.ArgumentParser(prog="python -m vo_lib", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    from vo_lib.sim.samples import SAMPLES

    run = sub.add_parser("run", help="run the stereo visual odometry pipeline")
    run.add_argument("--sequence", help="sample name or KITTI-layout folder (default: indoor_linear)")
    run.add_argument("--out", help="output folder (default: runs/NAME)")
    run.add_argument("--frames", type=int, help="process only the first N frames")
    run.add_argument(
        "--no-odometry", action="store_true", help="ignore odometry.txt (constant-velocity prediction)"
    )
    run.add_argument("--seed", type=int, default=0, help="seed of the RANSAC draws")
    ev = sub.add_parser("evaluate", help="ATE, RPE and KITTI segment errors of an estimate")
    ev.add_argument("--gt", required=True, help="ground-truth poses (KITTI poses.txt or TUM)")
    ev.add_argument("--est", required=True, help="estimated poses (KITTI or TUM)")
    ev.add_argument(
        "--segments", help="comma-separated segment lengths in metres (default: KITTI's 100..800)"
    )
    gen = sub.add_parser("generate", help="render a named sample sequence")
    gen.add_argument("name", choices=sorted(SAMPLES), help="which sample")
    gen.add_argument("--out", help="output folder (default: data/NAME)")
    gen.add_argument("--frames", type=int, help="keep only the first N frames")
    gen.add_argument(
        "--resolution", type=_resolution, default="640x480", help="WIDTHxHEIGHT (default 640x480)"
    )
    bench = sub.add_parser("bench", help="time a part of the library against a baseline")
    bench.add_argument("name", choices=sorted(BENCHES), help="which benchmark")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in ("run", "evaluate"):
        from vo_lib.cli.run import UsageError, evaluate_command, run_command

        try:
            if args.command == "run":
                run_command(args.sequence, args.out, args.frames, args.no_odometry, args.seed)
            else:
                evaluate_command(args.gt, args.est, args.segments)
        except UsageError as exc:
            parser.exit(2, f"python -m vo_lib {args.command}: error: {exc}\n")
    elif args.command == "generate":
        from vo_lib.data import sample_path
        from vo_lib.sim.samples import generate

        out = args.out or sample_path(args.name, args.frames, args.resolution)
        try:
            path = generate(args.name, out, args.frames, args.resolution)
        except (ValueError, OSError) as exc:
            parser.exit(2, f"python -m vo_lib generate: error: {exc}\n")
        print(f"wrote {path}")
    elif args.command == "bench":
        from vo_lib.cli.bench import BENCHES

        BENCHES[args.name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
