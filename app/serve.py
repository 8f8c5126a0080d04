"""``impact-explorer serve``: the app from wherever the package is installed.

    impact-explorer serve                      # http://localhost:5006/app, /liveness
    impact-explorer serve --port 8000 --num-procs 2
    impact-explorer serve --port 8000 --allow-websocket-origin classroom.example:8080

Runs ``panel serve`` on this package's app.py with ``--liveness``; every option it does
not know itself goes to ``panel serve`` unchanged (``panel serve --help`` lists them).
Allowed websocket origins default to ``IMPACT_ALLOWED_ORIGINS`` (comma-separated
host[:port]) or ``localhost:PORT``.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

APP_FILE = Path(__file__).resolve().parent / "app.py"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="impact-explorer", description="Impact Explorer: serve the web app",
        epilog="Unknown options are passed to `panel serve`.")
    sub = parser.add_subparsers(dest="command", required=True)
    serve = sub.add_parser("serve", help="serve the app (panel serve with --liveness)",
                           epilog="Any other option goes to `panel serve` unchanged.")
    serve.add_argument("--port", type=int, default=5006, help="port (default 5006)")
    serve.add_argument("--address", default=None, help="address to listen on (default: all)")
    serve.add_argument("--allow-websocket-origin", action="append", default=None,
                       metavar="HOST[:PORT]",
                       help="origin allowed to open the websocket (repeatable; default "
                            "IMPACT_ALLOWED_ORIGINS, else localhost:PORT)")
    serve.add_argument("--warmup", action="store_true",
                       help="compile the Numba kernels before serving (else the first page does)")
    return parser


def panel_command(args, extra: list[str]) -> list[str]:
    """The ``panel serve`` command line for parsed ``args`` and pass-through ``extra``."""
    if not 0 < args.port < 65536:
        raise SystemExit(f"impact-explorer serve: --port={args.port} must lie in 1..65535")
    origins = args.allow_websocket_origin
    if not origins:
        env = os.environ.get("IMPACT_ALLOWED_ORIGINS", "")
        origins = [o.strip() for o in env.split(",") if o.strip()] or [f"localhost:{args.port}"]
    if any("*" in o for o in origins):
        raise SystemExit("impact-explorer serve: allowed origins must be host[:port]; '*' is refused")
    cmd = [sys.executable, "-m", "panel", "serve", str(APP_FILE), "--port", str(args.port),
           "--liveness"]
    if args.address:
        cmd += ["--address", args.address]
    for o in origins:
        cmd += ["--allow-websocket-origin", o]
    return cmd + extra


def main(argv=None) -> int:
    args, extra = build_parser().parse_known_args(argv)
    cmd = panel_command(args, extra)
    if args.warmup:
        import impactlib

        impactlib.warmup()
    if os.name == "posix":
        os.execv(cmd[0], cmd)   # the server takes this process's place (and its signals)
    return subprocess.call(cmd)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
