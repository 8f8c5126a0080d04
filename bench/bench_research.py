"""What the research views cost: the app's streamed regime map against one il.regime_map
call on the same grid (the streaming overhead), the time to its first rows, and the
basins picture the app asks for (first rows, whole grid).

Paper defaults (m = 1, c = 0.05, k = 1, g = 0), omega x r over [0.1, 5] x [0, 1];
basins at r = 0.8, omega = 2.62 over the app's window. Medians after a warm-up, in one
process. Prints only. ``--quick``: one repeat and a 100 x 100 map.

    .venv/bin/python bench/bench_research.py [--quick]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import impactlib as il  # noqa: E402
from app import research, state  # noqa: E402


def streamed(blocks) -> tuple[float, float, int]:
    """(seconds to the first block, seconds in all, rows done)."""
    tic = time.perf_counter()
    first, done = None, 0
    for block in blocks:
        first = first if first is not None else time.perf_counter() - tic
        done = block.rows_done
    return first, time.perf_counter() - tic, done


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    n_map, repeats = (100, 1) if args.quick else (200, 3)
    il.warmup()
    run = state.validate({**state.defaults(), "map_n": n_map})
    req = research.map_request(run)
    list(research.map_rows(research.map_request(
        state.validate({**state.defaults(), "map_n": 8}))))            # warm-up
    whole, first, total = [], [], []
    for _ in range(repeats):
        tic = time.perf_counter()
        il.regime_map(run.params, "omega", req.values_x, "r", req.values_y,
                      max_steps=research.MAP_MAX_STEPS, max_impacts=research.MAP_MAX_IMPACTS)
        whole.append(time.perf_counter() - tic)
        f, t, done = streamed(research.map_rows(req, wall_time=1e9))
        first.append(f)
        total.append(t)
    print(f"regime map {n_map} x {n_map} (omega x r, paper window), median of {repeats}:")
    print(f"  one il.regime_map call     {statistics.median(whole):7.2f} s")
    print(f"  app, streamed by rows      {statistics.median(total):7.2f} s "
          f"(x{statistics.median(total) / statistics.median(whole):.2f}); first rows after "
          f"{statistics.median(first):.3f} s")

    brun = state.validate({**state.defaults(), "omega": 2.62, "r": 0.8, "basins_n": 100})
    scene = il.simulate(brun.params, dense=4000)
    traj = {"x": scene.dense.x, "v": scene.dense.v}
    breq = research.BasinsRequest(brun, *research.basins_window(brun, traj), 100)
    streamed(research.basins_rows(research.BasinsRequest(brun, breq.x_range, breq.v_range, 8)))
    first, total = [], []
    for _ in range(repeats):
        f, t, _ = streamed(research.basins_rows(breq, wall_time=1e9))
        first.append(f)
        total.append(t)
    print(f"basins 100 x 100 at omega = 2.62, r = 0.8, window x {breq.x_range}, "
          f"v {breq.v_range}, median of {repeats}:")
    print(f"  whole grid {statistics.median(total):.2f} s; first rows after "
          f"{statistics.median(first):.3f} s")


if __name__ == "__main__":
    main()
