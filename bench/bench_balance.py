"""How evenly a 1000-value ω diagram's work spreads over the threads (the schedule of a
fixed split against blocks handed out on demand, impactlib.parallel.run_blocks), and
what its serial merge costs.

    .venv/bin/python bench/bench_balance.py [--workers 2]

Each value's cost is measured alone (its kernel's time, the fastest of 3 after a
warm-up), with and without the tangent (lyapunov=True). Then both schedules are played
with these costs: the makespan (when the last thread finishes) over the ideal (total
work / threads). The wall clock of the real sweeps is printed too (medians, same
process), with the merge's rows ordered run by run (diagrams.row_order) and, for
comparison, by a lexsort of every row: that sort ran in the caller's thread after the
workers finished, the serial part that capped the speed-up.

Fixed split: ``4 x workers`` interleaved chunks (value j to chunk j mod chunks) queued on
the pool in turn (how the Lyapunov sweep handed out its values). On demand: the order
and block sizes of run_blocks (a quarter of the remaining values per worker, taken from
a shared counter by whichever thread is free).
"""
from __future__ import annotations

import argparse
import heapq
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import impactlib as il  # noqa: E402
from impactlib.analysis.lyapunov import lyapunov_run  # noqa: E402
from impactlib.sweeps import diagrams  # noqa: E402
from impactlib.sweeps.diagrams import BLOCK_OUTPUT, interleaved  # noqa: E402

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)
OMEGAS = np.linspace(0.1, 5.0, 1000)
CAP = 4096          # bifurcation's default cap_per_value


def value_costs(lyapunov: bool) -> np.ndarray:
    """Seconds of each value's run alone, in the kernel only (the fastest of 3: the
    least disturbed by other processes): ``Solution.elapsed`` of il.simulate, or the
    tangent-carrying run behind il.lyapunov timed around its engine call."""
    costs = np.empty(OMEGAS.size)
    for i, w in enumerate(OMEGAS):
        p = PAPER.replace(omega=float(w))
        ts = []
        for _ in range(4):
            if lyapunov:
                tic = time.perf_counter()
                lyapunov_run(p, 0.0, 0.0, 0.0, 500.0, 250.0)
                ts.append(time.perf_counter() - tic)
            else:
                ts.append(il.simulate(p, 500.0, t_record=250.0).elapsed)
        costs[i] = min(ts[1:])
    return costs


def list_schedule(tasks: list[float], workers: int) -> float:
    """Makespan of tasks taken in order by whichever of ``workers`` threads is free."""
    free = [0.0] * workers
    for cost in tasks:
        heapq.heappush(free, heapq.heappop(free) + cost)
    return max(free)


def fixed_split(costs: np.ndarray, workers: int) -> float:
    n = costs.size
    chunks = min(n, max(4 * workers, int(np.ceil(n / 128))))
    return list_schedule([costs[j::chunks].sum() for j in range(chunks)], workers)


def on_demand(costs: np.ndarray, workers: int) -> float:
    """run_blocks' blocks: the next min(max_block, remaining // (4 workers)) values of
    the interleaved order, to the thread that is free first."""
    n = costs.size
    order = interleaved(n)
    max_block = max(1, BLOCK_OUTPUT // CAP)
    free = [0.0] * workers
    a = 0
    while a < n:
        b = min(n, a + max(1, min(max_block, (n - a) // (4 * workers))))
        heapq.heappush(free, heapq.heappop(free) + costs[order[a:b]].sum())
        a = b
    return max(free)


ROW_ORDER = diagrams.row_order


def full_lexsort(index, direction, t):
    """The merge's row order by a lexsort of every row (the alternative measured)."""
    return np.lexsort((t, -direction, index))


def wall(fn, reps=5) -> float:
    fn()
    ts = []
    for _ in range(reps):
        tic = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - tic)
    return float(np.median(ts))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    w = ap.parse_args().workers
    for lyapunov in (False, True):
        costs = value_costs(lyapunov)
        ideal = costs.sum() / w
        top = np.sort(costs)[::-1]
        print(f"lyapunov={lyapunov}: {1e3 * costs.sum():.0f} ms of kernel time over "
              f"{costs.size} values; the costliest 5% hold "
              f"{100 * top[:costs.size // 20].sum() / costs.sum():.0f}% of it")
        print(f"  {w} threads, makespan / ideal: fixed split "
              f"{fixed_split(costs, w) / ideal:.3f}, on demand {on_demand(costs, w) / ideal:.3f}")
        run = lambda k: il.bifurcation(PAPER, "omega", OMEGAS, 500.0, 250.0,  # noqa: E731
                                       workers=k, lyapunov=lyapunov)
        times = {}
        for label, order in (("rows ordered by run", diagrams.row_order),
                             ("rows lexsorted", full_lexsort)):
            diagrams.row_order = order
            times[label] = wall(lambda: run(1)), wall(lambda: run(w))
        diagrams.row_order = ROW_ORDER
        for label, (t1, tw) in times.items():
            print(f"  wall clock (this machine, now), {label}: 1 thread {1e3 * t1:.0f} ms, "
                  f"{w} threads {1e3 * tw:.0f} ms, speed-up {t1 / tw:.2f}")


if __name__ == "__main__":
    main()
