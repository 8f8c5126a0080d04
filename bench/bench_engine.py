"""The exact engine's cost per impact, by parts (issue 18's profile).

    .venv/bin/python bench/bench_engine.py [--calls N] [--omega W ...]

The flights of one exact run (paper defaults unless --omega) are replayed in jitted loops
that each add one part of the engine's work per impact: the segment's set-up, the impact
search (with the engine's guess from the hop memory, the hop's own length, and without
a guess), what follows the impact; the whole run per impact last.  The differences
between the loops are each part's cost; counts (closed-form evaluations, grid nodes,
fallbacks to the certified walk) come from the same flights.  The loops pass what the
engine passes: tuples from flight.make_segment where the checkout has it, else arrays
from start_segment.  Medians over repeats in one process; run it against another
checkout (``PYTHONPATH``-free: the checkout is this file's parent) in the same minutes to
compare.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import impactlib as il  # noqa: E402
from impactlib.kernels import engine as E  # noqa: E402
from impactlib.kernels import events as EV  # noqa: E402
from impactlib.kernels import flight as F  # noqa: E402

try:        # the grid search's own module; older checkouts keep it in events.py
    from impactlib.kernels import grid as GR  # noqa: E402
except ImportError:
    GR = EV
from impactlib.kernels.chatter import impact_outcome  # noqa: E402
from impactlib.kernels.entry import run_constants, simulate_run  # noqa: E402

#: the engine's segment: a tuple (make_segment) or, in older checkouts, an array
make_segment = getattr(F, "make_segment", F.start_segment)
TUPLES = make_segment is not F.start_segment

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)
T_END, T_RECORD = 500.0, 250.0


@njit(cache=False)
def loop_segments(sp, t0s, x0s, v0s, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(t0s.shape[0]):
            seg = make_segment(sp, t0s[i], x0s[i], v0s[i])
            acc += seg[F.H0]
    return acc


@njit(cache=False)
def loop_flight_state(sp, t0s, x0s, v0s, ss, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(t0s.shape[0]):
            seg = make_segment(sp, t0s[i], x0s[i], v0s[i])
            x, v, a, j, rh, xs = F.flight_state(sp, seg, 0.5 * ss[i])
            acc += x
    return acc


@njit(cache=False)
def loop_search(sp, t0s, x0s, v0s, s_ends, guesses, hmax, grid, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(t0s.shape[0]):
            seg = make_segment(sp, t0s[i], x0s[i], v0s[i])
            kind, s, vh, ns = GR.next_impact_grid(sp, seg, s_ends[i], hmax, 10**7, grid,
                                                  guesses[i])
            acc += s
    return acc


@njit(cache=False)
def loop_outcome(sp, ts, vplus, rate, t_end, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(ts.shape[0]):
            mode, tn = impact_outcome(sp, ts[i], vplus[i], rate, E.TAIL_TOL, t_end)
            acc += tn
    return acc


@njit(cache=False)
def search_counts(sp, t0s, x0s, v0s, s_ends, guesses, hmax, grid):
    """Per flight: closed-form evaluations, whether the certified walk was needed (its
    own evaluations counted alone), and the grid nodes to the interval searched."""
    n = t0s.shape[0]
    evals = np.zeros(n)
    walk = np.zeros(n)
    nodes = np.zeros(n)
    for i in range(n):
        seg = F.start_segment(sp, t0s[i], x0s[i], v0s[i])
        kind, s, vh, ns = GR.next_impact_grid(sp, seg, s_ends[i], hmax, 10**7, grid,
                                              guesses[i])
        evals[i] = ns
        k2, s2, v2, n2 = EV.next_impact(sp, seg, s_ends[i], hmax, 10**7)
        walk[i] = 1.0 if ns >= n2 and s == s2 else 0.0
        h = grid[GR.GSTEP]
        nodes[i] = np.floor(s / h) + 1.0 if h > 0.0 else 0.0
    return evals, walk, nodes


def flights(p, t_end=T_END):
    """The flights of one exact run from simulate()'s default start: start times, states,
    lengths (to the next impact or t_end) and the engine's hop-memory guesses."""
    sol = il.simulate(p, t_end, t_record=0.0)
    t = sol.impacts.t
    vplus = np.maximum(-p.r * sol.impacts.v, 0.0)
    x_start = max(0.0, p.g)
    t0s = np.concatenate([[0.0], t])
    x0s = np.concatenate([[x_start], np.full(t.shape, p.g)])
    v0s = np.concatenate([[0.0], vplus])
    s = np.diff(np.concatenate([t0s, [t_end]]))
    # the engine's guess: the last remembered hop that left this close in speed
    guesses = np.full(t0s.shape, -1.0)
    mem_v = np.full(E.HOP_MEMORY, -1.0)
    mem_s = np.zeros(E.HOP_MEMORY)
    n_hop = 0
    for i in range(t0s.shape[0]):
        best = E.HOP_MATCH_RTOL * v0s[i]
        for jh in range(E.HOP_MEMORY):
            if abs(mem_v[jh] - v0s[i]) < best:
                best = abs(mem_v[jh] - v0s[i])
                guesses[i] = mem_s[jh]
        if i < t.shape[0] and v0s[i] > 0.0:
            mem_v[n_hop % E.HOP_MEMORY] = v0s[i]
            mem_s[n_hop % E.HOP_MEMORY] = s[i]
            n_hop += 1
    stuck = sol.sticking.shape[0] > 0 or sol.n_chatter > 0
    return sol, t0s, x0s, v0s, s, guesses, stuck


def median_ns(fn, per, repeats):
    fn()
    out = []
    for _ in range(repeats):
        tic = time.perf_counter()
        fn()
        out.append(time.perf_counter() - tic)
    return float(np.median(out)) / per * 1e9


def profile(p, reps, repeats):
    sol, t0s, x0s, v0s, s, guesses, stuck = flights(p)
    sp, rate, hmax = run_constants(p.m, p.c, p.k, p.g, p.r, p.omega)
    grid = GR.search_grid(sp, rate)
    s_ends = T_END - t0s
    n = t0s.shape[0]
    per = n * reps
    out = {"impacts": sol.n_impacts, "flights": n, "nsteps": sol.nsteps,
           "stuck/chatter": stuck}
    if TUPLES:
        sp, grid = tuple(sp), tuple(grid)
    out["segment"] = median_ns(lambda: loop_segments(sp, t0s, x0s, v0s, reps), per, repeats)
    out["segment+flight_state"] = median_ns(lambda: loop_flight_state(sp, t0s, x0s, v0s, s, reps), per,
                                    repeats)
    for name, gs in (("engine guess", guesses), ("exact guess", s), ("no guess", np.full(n, -1.0))):
        out["segment+search, " + name] = median_ns(
            lambda: loop_search(sp, t0s, x0s, v0s, s_ends, gs, hmax, grid, reps), per, repeats)
    out["impact_outcome"] = median_ns(
        lambda: loop_outcome(sp, t0s[1:], v0s[1:], rate, T_END, reps), max(1, n - 1) * reps,
        repeats)
    none = np.empty(0)
    run = lambda: simulate_run(p.m, p.c, p.k, p.g, p.r, p.omega, 0.0, max(0.0, p.g), 0.0,  # noqa: E731
                               T_RECORD, T_END, 0.0, E.EXACT, 0.0, 1e-6, 1e-9, 1e6, 20_000_000,
                               none)
    empty = lambda: simulate_run(p.m, p.c, p.k, p.g, p.r, p.omega, 0.0, 0.0, 0.0, 0.0, 1e-300,  # noqa: E731
                                 0.0, E.EXACT, 0.0, 1e-6, 1e-9, 1e6, 20_000_000, none)
    t_run = median_ns(lambda: [run() for _ in range(reps)], reps, repeats)
    t_empty = median_ns(lambda: [empty() for _ in range(reps)], reps, repeats)
    out["simulate_run (ns per call)"] = t_run
    out["entry fixed cost (ns)"] = t_empty
    out["engine per flight"] = (t_run - t_empty) / n
    ev, walk, nodes = search_counts(np.asarray(sp), t0s, x0s, v0s, s_ends, guesses, hmax,
                                    np.asarray(grid))
    out["evals per flight"] = float(ev.mean())
    out["grid nodes per flight"] = float(nodes.mean())
    out["walk fallbacks"] = int(walk.sum())
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--omega", type=float, nargs="*", default=[2.0])
    args = ap.parse_args()
    print(f"checkout {ROOT} ({'tuples' if TUPLES else 'arrays'}); load {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    for w in args.omega:
        out = profile(PAPER.replace(omega=w), args.reps, args.repeats)
        print(f"omega = {w}")
        for k, v in out.items():
            print(f"  {k:32s} {v:10.1f}" if isinstance(v, float) else f"  {k:32s} {v!s:>10}")


if __name__ == "__main__":
    main()
