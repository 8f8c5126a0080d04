"""Command line: ``impactlib`` (or ``python -m impactlib``) with the run commands of
:mod:`impactlib.commands` (simulate, bifurcation, regime-map, orbit, basins) and
``accuracy``, the error-against-run-time report."""
from __future__ import annotations

import argparse
import importlib
import sys

from . import commands

#: what the accuracy report needs beyond the core (the extra ``report`` of pyproject.toml)
REPORT_MODULES = ("mpmath", "matplotlib")


def _importable(name: str) -> bool:
    try:
        importlib.import_module(name)
    except ImportError:
        return False
    return True


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="impactlib",
                                     description="impactlib command line tools")
    sub = parser.add_subparsers(dest="command", required=True)
    commands.add_parsers(sub)
    acc = sub.add_parser("accuracy", help="error against run time of exact, rk4 and rk45 "
                         "against independent references (table, Markdown and PNG plot)")
    acc.add_argument("--quick", action="store_true",
                     help="only the cases marked quick, five method settings and 3 repeats "
                          "(the full report runs every case, more settings, 7 repeats)")
    acc.add_argument("--out", default=None, metavar="DIR",
                     help="directory to write BENCHMARKS-accuracy.md and accuracy.png into "
                          "(created if missing; the repository keeps its copy in bench/)")
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in commands.COMMANDS:
        return commands.run(args)
    if args.command == "accuracy" and args.out is None:
        parser.error("accuracy needs --out DIR: where to write BENCHMARKS-accuracy.md and "
                     "accuracy.png")
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
