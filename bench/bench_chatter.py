"""What summing chatters early saves: the 1000-value omega diagram's kernel time and the
share of its values with a summed chatter, the impacts (hops) resolved per chatter, the
diagram's wall time on 2 threads and (with --map) the 200 x 200 regime map.

    .venv/bin/python bench/bench_chatter.py            # prints
    .venv/bin/python bench/bench_chatter.py --map      # ... plus the regime map's wall and CPU

Run it from two checkouts in the same minute to compare two versions of the chatter
handling (each copy imports its own impactlib).  Kernel times are the minimum of seven
runs of each value alone (``Solution.elapsed``); walls are medians after a warm-up.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import impactlib as il  # noqa: E402
from bench_speed import (OMEGAS, PAPER, T_END, T_RECORD, diagram_values,  # noqa: E402
                         regime_grid)


def timed(fn, reps):
    fn()
    walls, cpus = [], []
    for _ in range(reps):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return float(np.median(walls)), float(np.median(cpus))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", action="store_true", help="also time the 200 x 200 regime map")
    ap.add_argument("--reps", type=int, default=7, help="repeats of the 2-thread diagram")
    args = ap.parse_args(argv)
    il.simulate(PAPER, T_END, t_record=T_RECORD)
    _, cost, ev, n_imp, n_ch, _ = diagram_values(repeats=7).T
    chat = n_ch > 0
    tot = cost.sum()
    print(f"impactlib from {Path(il.__file__).parent}")
    print(f"diagram kernel time {tot * 1e3:.1f} ms; {int(chat.sum())} values with a summed "
          f"chatter take {cost[chat].sum() * 1e3:.1f} ms ({100 * cost[chat].sum() / tot:.0f}%)")
    print(f"  chatter values: {int(n_ch[chat].sum())} chatters, {int(n_imp[chat].sum())} impacts "
          f"({n_imp[chat].sum() / n_ch[chat].sum():.1f} per chatter summed), "
          f"{int(ev[chat].sum())} closed-form evaluations")
    wall, cpu = timed(lambda: il.bifurcation(PAPER, "omega", OMEGAS, T_END, T_RECORD, workers=2),
                      args.reps)
    print(f"diagram on 2 threads: wall {wall * 1e3:.1f} ms, CPU {cpu * 1e3:.1f} ms (medians)")
    if args.map:
        wx, wy = regime_grid(200)
        wall, cpu = timed(lambda: il.regime_map(PAPER, "omega", wx, "r", wy, workers=2), 1)
        print(f"regime map 200 x 200 on 2 threads: wall {wall:.2f} s, CPU {cpu:.2f} s")


if __name__ == "__main__":
    main()
