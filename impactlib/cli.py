"""Command line: ``python -m impactlib accuracy [--quick] [--out DIR]``."""
from __future__ import annotations

import argparse
import sys


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m impactlib",
                                     description="impactlib command line tools")
    sub = parser.add_subparsers(dest="command", required=True)
    acc = sub.add_parser("accuracy", help="error against run time of exact, rk4 and rk45 "
                         "against independent references (table, Markdown and PNG plot)")
    acc.add_argument("--quick", action="store_true",
                     help="fewer cases and settings (about a minute)")
    acc.add_argument("--out", default="bench", metavar="DIR",
                     help="directory for BENCHMARKS-accuracy.md and accuracy.png "
                          "(default: bench)")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "accuracy":
        from .accuracy import main as accuracy_main
        return accuracy_main(quick=args.quick, out=args.out)
    return 2  # pragma: no cover  (argparse rejects other commands)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
