"""What a boundary curve costs: the period-doubling curves of the 1-impact period-1 orbit
across the paper's (omega, r) box [0.5, 5] x [0, 1] (m = 1, c = 0.05, k = 1, g = 0), by
il.boundary, against the way without it: one il.continuation in omega at each of as many
fixed r values as the curve has points, each locating the period-doublings.

The lower curve starts at r = 1 on the period-doubling near omega = 1.255, turns in r
near 0.636 and comes back to r = 1 near omega = 1.012: the curve that bends.  The upper
one runs from r = 1 to r = 0 near omega = 2.65-2.76.  Medians after a warm-up, in one
process.  Prints only.  ``--quick``: one repeat; ``--overlay``: also the app's boundary
overlay for the default regime map box (app.boundaries, without its time bound; seeded
from the branches alone, then also from the default map's regions), and its
curves' CPU time with the corrector against its alternative (every column of the whole
residual by differences, a Jacobian of its own for each tangent).

    .venv/bin/python bench/bench_boundary.py [--quick] [--overlay]
"""
from __future__ import annotations

import argparse
import math
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
        overlay(repeats)


def full_jacobian(self, y):
    """The corrector's Jacobian with every (t, u) column by central differences of the
    whole residual (the alternative to ``CurveSystem.jacobian``, which differentiates only
    the conditions, at the unknowns they depend on)."""
    m2 = 2 * self.m
    H = self.residual(y)
    J = np.zeros((self.nz - 1, self.nz))
    J[:m2, :m2] = self.DF
    for i in range(self.nz):
        h = (1e-6 * max(1.0, abs(y[i]))) if i >= self.nz - 2 else 1e-7 * (1.0 + abs(y[i]))
        yp, ym = y.copy(), y.copy()
        yp[i] += h
        ym[i] -= h
        try:
            hp = self.residual(yp)
        except ValueError:
            hp, yp = H, y
        try:
            hm = self.residual(ym)
        except ValueError:
            hm, ym = H, y
        col = (hp - hm) / (yp[i] - ym[i])
        if i < m2:
            J[m2:, i] = col[m2:]
        else:
            J[:, i] = col
    return H, J


def overlay(repeats: int) -> None:
    """The app's boundary overlay for the default regime map box, without its time bound:
    seconds to the first curve and to all of them (one run); then its curves alone, CPU
    time (one thread: less disturbed by other work on a shared machine), with the
    corrector as it is against the alternative of ``full_jacobian`` and a tangent from a
    Jacobian of its own at every point, alternated, medians of ``repeats``."""
    from app import boundaries, map_seeds, research, state
    from impactlib.analysis import boundary_system as bmod
    boundaries.WALL_TIME = float("inf")
    run = state.validate(state.defaults())
    mreq = research.map_request(run)
    tic = time.perf_counter()
    blocks = list(research.map_rows(mreq, wall_time=float("inf")))
    print(f"app regime map, default box ({run.map_n} x {run.map_n}): "
          f"{time.perf_counter() - tic:.2f} s (what the overlay's regions come from)")
    cells = map_seeds.MapCells.of(mreq.key(), mreq.values_x, mreq.values_y,
                                  np.concatenate([b.impacts for b in blocks]),
                                  np.concatenate([b.period for b in blocks]))
    for label, with_cells in (("branches at the current y only", None),
                              ("branches and the map's regions", cells)):
        boundaries.CACHE.clear()
        req = boundaries.BoundaryRequest(run, run.map_x, run.map_y, with_cells)
        tic, cpu = time.perf_counter(), time.process_time()
        first, last = None, None
        for last in boundaries.compute(req):
            if first is None and last.curves:
                first = time.perf_counter() - tic
        total, cpu = time.perf_counter() - tic, time.process_time() - cpu
        print(f"app overlay, default box ({run.map_x} x {run.map_y}, {run.map_y} = "
              f"{getattr(run.params, run.map_y):g}), {label}: first curve {first:.2f} s, all "
              f"{total:.2f} s ({cpu:.2f} s CPU); {last.message}")
    req = boundaries.BoundaryRequest(run, run.map_x, run.map_y)
    tic = time.process_time()
    events = boundaries.branch_events(req, lambda: True, math.inf)
    seeds = time.process_time() - tic
    lo, hi = boundaries.SWEEP_RANGES[req.name_y]
    jobs = [(e, stop) for e in events for stop in (lo, hi)
            if stop != getattr(e.params, req.name_y)]

    def curves():
        tic = time.process_time()
        points = sum(len(il.boundary(e, req.name_y, stop, ds=boundaries.STEP * (hi - lo),
                                     max_points=boundaries.MAX_POINTS).values)
                     for e, stop in jobs)
        return time.process_time() - tic, points
    jacobian, tangent = bmod.CurveSystem.jacobian, bmod.CurveSystem.tangent
    times = {"as is": [], "alternative": []}
    points = {}
    for _ in range(repeats):
        for label in times:
            if label == "alternative":
                bmod.CurveSystem.jacobian = full_jacobian
                bmod.CurveSystem.tangent = lambda self, y, t_prev=None, J=None: tangent(self, y, t_prev)
            try:
                t, points[label] = curves()
            finally:
                bmod.CurveSystem.jacobian, bmod.CurveSystem.tangent = jacobian, tangent
            times[label].append(t)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"  seeds and branches: {seeds:.2f} s CPU, {len(events)} events, {len(jobs)} curves")
    for label in times:
        print(f"  curves, corrector {label}: {med[label]:.2f} s CPU (median of {repeats}), "
              f"{points[label]} points")
    print(f"  ratio: x{med['alternative'] / med['as is']:.2f}")


if __name__ == "__main__":
    main()
