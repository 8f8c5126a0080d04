"""Basins benchmark (issue 9): a 100 x 100 basin grid and the time to its first rows.

    .venv/bin/python bench/bench_basins.py            # medians of 5 after a warm-up
    .venv/bin/python bench/bench_basins.py --quick    # 2 repeats, smaller alternative

Scenes: r = 0.8 with omega = 2.62 (period-1 and 3-impact period-3 coexist), 2.64
(period-1 and 6-impact period-6) and 2.8 (the paper's chaotic Fig. 6), all on x in
[0, 1], v in [-1.5, 1.5] at phase 0.  Reported per scene: whole grid on all cores and on
one (the ratio shows the pool's use of the cores), time to the first yielded block of
``iter_basins``, periods followed per start.  The alternative a user has without
``basins``: one ``simulate`` of the paper's 500 s per start and ``classify`` of it
(timed on a spread subset in the same process, scaled to the grid).  All timings are
wall-clock medians of ``time.perf_counter`` after a warm-up call (Numba compile or cache
load) in this one process.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import impactlib as il  # noqa: E402
from impactlib.sweeps import worker_count  # noqa: E402

XR, VR, N = (0.0, 1.0), (-1.5, 1.5), (100, 100)
SCENES = [("r=0.8, omega=2.62", il.Params(r=0.8, omega=2.62)),
          ("r=0.8, omega=2.64", il.Params(r=0.8, omega=2.64)),
          ("r=0.8, omega=2.8 (chaotic)", il.Params(r=0.8, omega=2.8))]


def median_time(fn, repeats):
    ts, out = [], None
    for _ in range(repeats):
        tic = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - tic)
    return float(np.median(ts)), out


def first_rows(p):
    tic = time.perf_counter()
    gen = il.iter_basins(p, XR, VR, n=N)
    blk = next(gen)
    dt = time.perf_counter() - tic
    gen.close()
    return dt, blk


def brute_force(p, n_starts):
    """simulate(500 s) + classify per start, on n_starts spread over the grid."""
    xs = np.linspace(*XR, N[0])
    vs = np.linspace(*VR, N[1])
    idx = np.linspace(0, N[0] * N[1] - 1, n_starts).astype(int)
    for c in idx:
        i, j = divmod(int(c), N[0])
        il.classify(il.simulate(p, x0=xs[j], v0=vs[i], t_end=500.0, t_record=250.0))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    repeats = 2 if args.quick else 5
    n_alt = 100 if args.quick else 400
    print(f"impactlib basins benchmark; {os.cpu_count()} CPUs, pool of {worker_count()} "
          f"workers; grid {N[0]} x {N[1]}; medians of {repeats} after a warm-up")
    il.warmup()
    for name, p in SCENES:
        il.basins(p, XR, VR, n=(10, 10))                      # warm-up (compile or cache)
        t_all, b = median_time(lambda: il.basins(p, XR, VR, n=N), repeats)
        t_one, _ = median_time(lambda: il.basins(p, XR, VR, n=N, workers=1), repeats)
        t_first = float(np.median([first_rows(p)[0] for _ in range(repeats)]))
        _, blk = first_rows(p)
        t_alt, _ = median_time(lambda: brute_force(p, n_alt), 1 if args.quick else 3)
        t_alt_grid = t_alt * N[0] * N[1] / n_alt
        print(f"\n{name}")
        print("  attractors: " + "; ".join(f"{a.label} {f:.1%}"
                                           for a, f in zip(b.attractors, b.fractions))
              + f"; undecided {b.undecided:.1%}; {b.message}")
        print(f"  whole grid, all workers   {t_all:8.3f} s")
        print(f"  whole grid, 1 worker      {t_one:8.3f} s   (x{t_one / t_all:.2f} of all)")
        print(f"  first rows ({blk.labels.shape[0]} rows)     {t_first:8.3f} s")
        print(f"  periods per start         median {np.median(b.periods):.0f}, "
              f"mean {b.periods.mean():.0f}, max {b.periods.max()}")
        print(f"  simulate(500 s)+classify  {t_alt_grid:8.3f} s for the grid, 1 thread "
              f"(from {n_alt} starts; x{t_alt_grid / t_one:.1f} of basins on 1 worker)")


if __name__ == "__main__":
    main()
