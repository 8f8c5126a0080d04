"""Command line: ``python -m impactlib accuracy [--quick] [--out DIR]``."""
from __future__ import annotations

import argparse
import importlib
import sys

#: what the accuracy report needs beyond the core (the extra ``report`` of pyproject.toml)
REPORT_MODULES = ("mpmath", "matplotlib")


def _importable(name: str) -> bool:
    try:
        importlib.import_module(name)
    except ImportError:
        return False
    return True


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
        missing = [m for m in REPORT_MODULES if not _importable(m)]
        if missing:
            print(f"python -m impactlib accuracy needs the optional extra 'report' "
                  f"(missing: {', '.join(missing)}): pip install 'impact-explorer[report]'",
                  file=sys.stderr)
            return 2
        from .verify.report import main as report_main
        return report_main(quick=args.quick, out=args.out)
    return 2  # pragma: no cover  (argparse rejects other commands)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
