"""Cost of the app's stability pieces, in one process, after warm-up, as medians.

    .venv/bin/python bench/bench_app_stability.py           # about a minute
    .venv/bin/python bench/bench_app_stability.py --quick   # fewer repeats

* the stability readout of one scene, uncached (``app.stability._stability_readout``):
  settled periodic orbit (ω = 2), sticking (ω = 0.2), non-periodic with exponents (2.8);
* the default 400-value diagram as the app computes it (``app.diagram.compute_chunk``,
  which carries the Lyapunov strip) against the same sweep without the tangent
  (``lyapunov=False``), alternated: the strip's overhead in the app;
* the branch overlay of the default diagram and of r = 0.6 (seeds from the diagram,
  continuation, doubled branches), uncached.

Prints only. Figures from a shared machine are noisy: compare ratios from one run.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import impactlib as il  # noqa: E402
from app import branches, diagram, stability, state  # noqa: E402


def run_of(**query) -> state.Run:
    return state.validate(state.parse_query({k: str(v) for k, v in query.items()})[0])


def median_time(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    reps = 3 if args.quick else 9
    il.warmup()

    print("stability readout, uncached (median ms):")
    for omega in (2.0, 0.2, 2.8):
        key = stability.readout_key(run_of(omega=omega))
        stability._stability_readout(key, None)                       # warm-up
        ms = 1e3 * median_time(lambda: stability._stability_readout(key, None), reps)
        kind = stability._stability_readout(key, None).kind
        print(f"  omega = {omega:<4}  {kind:<9}  {ms:8.2f} ms")

    run = run_of()
    values = np.sort(diagram.sweep_values(run))

    def plain():
        il.bifurcation(run.params, run.bif_param, values, t_end=run.t_end,
                       t_record=run.t_record, method="exact", x0=run.x0, v0=run.v0,
                       cap_per_value=diagram.MAX_IMPACTS_PER_VALUE,
                       max_impacts=diagram.DIAGRAM_MAX_IMPACTS_PER_500S,
                       max_steps=diagram.DIAGRAM_MAX_STEPS_PER_500S)

    def with_strip():
        diagram.compute_chunk(run, values)

    plain(), with_strip()
    a, b = [], []
    for _ in range(reps):
        a.append(median_time(plain, 1))
        b.append(median_time(with_strip, 1))
    pa, pb = statistics.median(a), statistics.median(b)
    print(f"400-value diagram: without strip {pa * 1e3:.0f} ms, as the app computes it "
          f"(with strip) {pb * 1e3:.0f} ms, ratio {pb / pa:.2f}")

    print("branch overlay, uncached (median s):")
    for query in ({}, {"r": 0.6}):
        run = run_of(**query)
        part = diagram.compute_chunk(run, np.sort(diagram.sweep_values(run)))
        seeds = branches.seeds(part["values"], part["lyapunov"], part["omega"], part["drawn"])
        s = median_time(lambda: branches.compute(run, seeds), max(1, reps // 3))
        result = branches.compute(run, seeds)
        print(f"  {query or 'paper defaults'}: {s:.2f} s, {result.message}")


if __name__ == "__main__":
    main()
