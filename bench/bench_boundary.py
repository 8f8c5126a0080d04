"""What a boundary curve costs: the period-doubling curves of the 1-impact period-1 orbit
across the paper's (omega, r) box [0.5, 5] x [0, 1] (m = 1, c = 0.05, k = 1, g = 0), by
il.boundary, against the way without it: one il.continuation in omega at each of as many
fixed r values as the curve has points, each locating the period-doublings.

The lower curve starts at r = 1 on the period-doubling near omega = 1.255, turns in r
near 0.636 and comes back to r = 1 near omega = 1.012: the curve that bends.  The upper
one runs from r = 1 to r = 0 near omega = 2.65-2.76.  Medians after a warm-up, in one
process.  Prints only.  ``--quick``: one repeat; ``--overlay``: also the app's boundary
overlay for the default regime map box (app.boundaries, without its time bound).

    .venv/bin/python bench/bench_boundary.py [--quick] [--overlay]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import impactlib as il  # noqa: E402

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)
DS = 0.003          # largest move in the (omega, r) plane per step


def timed(f, repeats):
    times, out = [], None
    for _ in range(repeats):
        tic = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - tic)
    return statistics.median(times), out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--overlay", action="store_true",
                    help="also time the app's boundary overlay for the default map box")
    args = ap.parse_args()
    repeats = 1 if args.quick else 5
    p1 = PAPER.replace(r=1.0)
    lower_start = il.continuation(p1, "omega", 0.5).events[0]
    upper_start = il.continuation(p1, "omega", 5.0).events[0]
    il.boundary(lower_start, "r", 0.0, max_points=20)             # warm-up
    print(f"period-doubling curves of the 1-impact period-1 orbit, (omega, r) box "
          f"[0.5, 5] x [0, 1], ds = {DS}, median of {repeats}:")
    for label, e in (("lower (bends)", lower_start), ("upper", upper_start)):
        t, b = timed(lambda: il.boundary(e, "r", 0.0, ds=DS), repeats)
        w, r = b.values[:, 0], b.values[:, 1]
        inside = np.count_nonzero((w >= 0.5) & (w <= 5.0))
        # points where the curve turns: its direction in the plane changes
        d = np.diff(b.values, axis=0)
        ang = np.abs(np.diff(np.unwrap(np.arctan2(d[:, 1], d[:, 0]))))
        print(f"  {label:14s} {t:6.3f} s  {len(w)} points ({inside} in the box), "
              f"r in [{r.min():.4f}, {r.max():.4f}], omega in [{w.min():.4f}, {w.max():.4f}], "
              f"turns {np.degrees(ang.sum()):.0f} degrees; {b.message}")
        if label.startswith("lower"):
            n_lower, t_lower = len(w), t
            r_values = np.linspace(r.min() + 1e-3, 1.0, n_lower // 2)
    # the alternative: one-parameter branches at fixed r (half as many as the curve has
    # points, each crossing the curve twice), each locating both period-doublings
    def by_branches():
        found = 0
        for rv in r_values:
            br = il.continuation(PAPER.replace(r=float(rv)), "omega", 0.9)
            found += sum(e.kind == "period-doubling" for e in br.events)
        return found
    t_alt, found = timed(by_branches, 1)
    print(f"  alternative: {len(r_values)} branches at fixed r, {t_alt:6.3f} s, "
          f"{found} period-doublings (x{t_alt / t_lower:.1f} the curve's time)")
    if args.overlay:
        overlay()


def overlay() -> None:
    """The app's boundary overlay for the default regime map box, without its time bound:
    seconds to the first curve and to all of them (one run)."""
    from app import boundaries, state
    boundaries.WALL_TIME = float("inf")
    run = state.validate(state.defaults())
    req = boundaries.BoundaryRequest(run, run.map_x, run.map_y)
    tic = time.perf_counter()
    first, last = None, None
    for last in boundaries.compute(req):
        if first is None and last.curves:
            first = time.perf_counter() - tic
    total = time.perf_counter() - tic
    print(f"app overlay, default box ({run.map_x} x {run.map_y}, {run.map_y} = "
          f"{getattr(run.params, run.map_y):g} seeds): first curve {first:.2f} s, all "
          f"{total:.2f} s; {last.message}")


if __name__ == "__main__":
    main()
