"""The run commands of the command line: simulate, bifurcation, regime-map, orbit, basins.

Each takes the physical parameters as ``--m --c --k --g --r --omega`` (default the
paper's), the settings under the names of the Python function (``--t-end`` for
``t_end``), runs the function and writes its table: CSV with the ``# name = value``
settings block (to ``--out FILE.csv``, or standard output), or netCDF for the sweeps and
grids (``--out FILE.nc``, needs xarray). The numbers are the Python API's, written with 17
significant digits.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

import impactlib as il

from .model import FIELDS, PARAM_NAMES, Params


def number(text: str) -> float:
    """argparse type: a finite number (nan, inf and text are refused, naming the option)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _add_params(parser):
    g = parser.add_argument_group("parameters (default: the paper's)")
    for name in PARAM_NAMES:
        f = FIELDS[name]
        g.add_argument(f"--{name}", type=number, default=getattr(Params(), name),
                       help=f"{f.doc} (default %(default)s)")


def _add_run(parser, t_end=500.0, t_record=None, method=True):
    g = parser.add_argument_group("run")
    g.add_argument("--t-end", type=number, default=t_end, help="end of each run, s (default %(default)s)")
    g.add_argument("--t-record", type=number, default=t_record,
                   help="start of the record window, s (default %s)" %
                        ("t_end / 2" if t_record is None else t_record))
    g.add_argument("--x0", type=number, default=None, help="start position (default max(0, g))")
    g.add_argument("--v0", type=number, default=0.0, help="start velocity (default 0)")
    if method:
        g.add_argument("--method", default="exact", choices=("exact", "rk4", "rk45"))
        g.add_argument("--dt", type=number, default=None, help="rk4 step, s")
        g.add_argument("--rtol", type=number, default=1e-6, help="rk45 relative tolerance")
        g.add_argument("--atol", type=number, default=1e-9, help="rk45 absolute tolerance")


def _add_out(parser, tables=None, netcdf=True):
    parser.add_argument("--out", default="-", metavar="FILE",
                        help="output file: .csv" + (" or .nc (netCDF, needs xarray)" if netcdf else "")
                        + "; '-' (default) writes CSV to standard output")
    if tables:
        parser.add_argument("--table", choices=tables, default=tables[0],
                            help="which table to write (default %(default)s)")


def _progress_flag(parser):
    parser.add_argument("--progress", action="store_true",
                        help="a progress bar on standard error")


def add_parsers(sub) -> None:
    """Add the run commands to the subparsers ``sub`` of the main parser."""
    s = sub.add_parser("simulate", help="one run: impacts, Poincaré points, dense samples "
                       "or sticking intervals (impactlib.simulate)")
    _add_params(s)
    _add_run(s)
    s.add_argument("--phase", type=number, default=0.0, help="Poincaré section t = phase + nT, s")
    s.add_argument("--dense", type=int, default=0, help="evenly spaced samples of the window")
    _add_out(s, ("impacts", "poincare", "dense", "sticking"), netcdf=False)

    b = sub.add_parser("bifurcation", help="impact velocities against one parameter "
                       "(impactlib.bifurcation)")
    _add_params(b)
    b.add_argument("--name", default="omega", choices=PARAM_NAMES, help="swept parameter")
    b.add_argument("--start", type=number, default=0.1, help="first value (default %(default)s)")
    b.add_argument("--stop", type=number, default=5.0, help="last value (default %(default)s)")
    b.add_argument("--num", type=int, default=200, help="values, evenly spaced (default %(default)s)")
    _add_run(b, t_record=250.0)
    b.add_argument("--warm-start", default="no", choices=("no", "up", "down", "both"),
                   help="each run from the previous one's end (default: independent)")
    b.add_argument("--lyapunov", action="store_true", help="also the largest Lyapunov exponent per value")
    _progress_flag(b)
    _add_out(b, ("impacts", "values"))

    r = sub.add_parser("regime-map", help="the motion class on a grid of two parameters "
                       "(impactlib.regime_map)")
    _add_params(r)
    for axis, name, lo, hi in (("x", "omega", 0.1, 5.0), ("y", "r", 0.0, 1.0)):
        r.add_argument(f"--name-{axis}", default=name, choices=PARAM_NAMES,
                       help=f"parameter along {axis} (default %(default)s)")
        r.add_argument(f"--{axis}-start", type=number, default=lo, help="first value (default %(default)s)")
        r.add_argument(f"--{axis}-stop", type=number, default=hi, help="last value (default %(default)s)")
        r.add_argument(f"--n{axis}", type=int, default=50, help="values (default %(default)s)")
    _add_run(r, t_record=250.0)
    _progress_flag(r)
    _add_out(r)

    o = sub.add_parser("orbit", help="a periodic orbit by Newton on the stroboscopic map, with "
                       "its multipliers (impactlib.periodic_orbit)")
    _add_params(o)
    o.add_argument("--n", type=int, default=1, help="forcing periods per orbit (default 1)")
    o.add_argument("--x0", type=number, default=None, help="Newton's start (default: settled from rest)")
    o.add_argument("--v0", type=number, default=None)
    o.add_argument("--phase", type=number, default=0.0, help="section, s")
    _add_out(o, netcdf=False)

    a = sub.add_parser("basins", help="which attractor each start of a grid settles on "
                       "(impactlib.basins)")
    _add_params(a)
    a.add_argument("--x-range", type=number, nargs=2, default=(0.0, 1.0), metavar=("LO", "HI"))
    a.add_argument("--v-range", type=number, nargs=2, default=(-1.5, 1.5), metavar=("LO", "HI"))
    a.add_argument("--n", type=int, nargs=2, default=(50, 50), metavar=("NX", "NV"))
    a.add_argument("--phase", type=number, default=0.0, help="section of the starts, s")
    a.add_argument("--max-periods", type=int, default=1000)
    a.add_argument("--time-limit", type=number, default=None, help="seconds; partial result after")
    _progress_flag(a)
    _add_out(a)


COMMANDS = ("simulate", "bifurcation", "regime-map", "orbit", "basins")


def _params(args) -> Params:
    return Params(**{n: getattr(args, n) for n in PARAM_NAMES})


def _method_kw(args):
    return dict(method=args.method, dt=args.dt, rtol=args.rtol, atol=args.atol)


def compute(args):
    """The result object of a parsed run command (the same call a script would make)."""
    p = _params(args)
    progress = getattr(args, "progress", False)
    if args.command == "simulate":
        return il.simulate(p, t_end=args.t_end, x0=args.x0, v0=args.v0, t_record=args.t_record,
                           phase=args.phase, dense=args.dense, **_method_kw(args))
    if args.command == "bifurcation":
        values = np.linspace(args.start, args.stop, args.num)
        warm = False if args.warm_start == "no" else args.warm_start
        return il.bifurcation(p, args.name, values, t_end=args.t_end,
                              t_record=args.t_record, x0=args.x0, v0=args.v0,
                              warm_start=warm, lyapunov=args.lyapunov,
                              progress=progress, **_method_kw(args))
    if args.command == "regime-map":
        vx = np.linspace(args.x_start, args.x_stop, args.nx)
        vy = np.linspace(args.y_start, args.y_stop, args.ny)
        return il.regime_map(p, args.name_x, vx, args.name_y, vy, t_end=args.t_end,
                             t_record=args.t_record, x0=args.x0, v0=args.v0,
                             progress=progress, **_method_kw(args))
    if args.command == "orbit":
        return il.periodic_orbit(p, n=args.n, x0=args.x0, v0=args.v0, phase=args.phase)
    if args.command == "basins":
        return il.basins(p, tuple(args.x_range), tuple(args.v_range), n=tuple(args.n),
                         phase=args.phase, max_periods=args.max_periods,
                         time_limit=args.time_limit, progress=progress)
    raise ValueError(f"unknown command {args.command!r}")  # pragma: no cover


def run(args) -> int:
    try:
        result = compute(args)
    except ValueError as err:
        print(f"impactlib {args.command}: {err}", file=sys.stderr)
        return 2
    table = getattr(args, "table", None)
    out = args.out
    if out.endswith(".nc"):
        if not hasattr(result, "to_xarray"):
            print(f"impactlib {args.command}: netCDF output is for sweeps and grids; "
                  "write .csv", file=sys.stderr)
            return 2
        try:
            ds = result.to_xarray()
        except ImportError as err:
            print(f"impactlib {args.command}: {err}", file=sys.stderr)
            return 2
        ds.to_netcdf(out)
    elif out == "-":
        result.to_csv(sys.stdout, table)
        sys.stdout.flush()
    else:
        result.to_csv(out, table)
    print(repr(result), file=sys.stderr)
    return 0
