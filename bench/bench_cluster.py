"""The app's regime map on a Dask cluster against the server's own threads.

The research view's stream (``app.research.map_rows``, the app's work ceilings per cell,
no wall-time cut) for a 400 x 400 map of omega x r over [0.1, 5] x [0, 1] at the paper's
defaults (a request built directly: the page's map_n setting stops at 300): on this process's threads, and with a client of a ``LocalCluster`` on this
machine (``--workers`` processes of one thread each; default 2, the cores here), as the
app does when IMPACT_DASK_SCHEDULER names a scheduler. Local and cluster runs alternate
after a warm-up of each; medians; the two maps' (m, n) codes are checked identical.
On one machine the cluster can only add overhead (the same cores, plus transfers); what
it buys is more machines. Prints only.

    .venv/bin/python bench/bench_cluster.py [--n 400] [--repeats 2] [--workers 2]
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
from app import research, state  # noqa: E402


def streamed(blocks):
    """(seconds to the first rows, seconds in all, impacts codes, period codes)."""
    tic = time.perf_counter()
    first, parts = None, []
    for block in blocks:
        first = first if first is not None else time.perf_counter() - tic
        parts.append(block)
    parts.sort(key=lambda b: b.start)
    return (first, time.perf_counter() - tic, np.concatenate([b.impacts for b in parts]),
            np.concatenate([b.period for b in parts]))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    import distributed

    il.warmup()
    # the request built directly: the page's map_n setting stops at 300 cells per side
    req = research.MapRequest(state.validate(state.defaults()), "omega", "r", args.n)
    small = research.map_request(state.validate({**state.defaults(), "map_n": 8}))
    with distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                  processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        client.run(il.warmup)                           # every worker compiles first
        streamed(research.map_rows(small))
        streamed(research.map_rows(small, client=client))
        here, there = [], []
        for _ in range(args.repeats):
            here.append(streamed(research.map_rows(req, wall_time=1e9)))
            there.append(streamed(research.map_rows(req, wall_time=1e9, client=client)))
    same = all(np.array_equal(a[2], b[2]) and np.array_equal(a[3], b[3])
               for a in here for b in there)
    med = {k: (statistics.median(r[1] for r in runs), statistics.median(r[0] for r in runs))
           for k, runs in (("here", here), ("there", there))}
    cells = args.n * args.n
    print(f"regime map {args.n} x {args.n} (omega x r, paper window, the app's ceilings), "
          f"median of {args.repeats}:")
    print(f"  server threads ({il.parallel.worker_count()})       {med['here'][0]:7.2f} s, "
          f"{cells / med['here'][0]:8.0f} cells/s, first rows after {med['here'][1]:.2f} s")
    print(f"  LocalCluster ({args.workers} processes x 1 thread) {med['there'][0]:7.2f} s, "
          f"{cells / med['there'][0]:8.0f} cells/s, first rows after {med['there'][1]:.2f} s "
          f"(x{med['there'][0] / med['here'][0]:.2f})")
    print(f"  identical (m, n) codes: {same}")


if __name__ == "__main__":
    main()
