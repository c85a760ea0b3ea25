"""Command line of the collection: ``python -m vo_lib COMMAND``.

Commands
--------
bench NAME     time one part of the library against its baseline (``bench --help`` lists them)
"""

from __future__ import annotations

import argparse
import sys


def build_parser() -> argparse.ArgumentParser:
    from vo_lib.bench import BENCHES

    parser = argparse.ArgumentParser(prog="python -m vo_lib", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    bench = sub.add_parser("bench", help="time a part of the library against a baseline")
    bench.add_argument("name", choices=sorted(BENCHES), help="which benchmark")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "bench":
        from vo_lib.bench import BENCHES

        BENCHES[args.name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
