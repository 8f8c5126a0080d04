"""The Python layer around one simulate() call: the call's time against its kernel's.

    .venv/bin/python bench/bench_call.py [--calls 5000]

One exact 500 s trajectory at the paper defaults (window [250, 500]), as bench_speed
times it. Four timings, interleaved call by call in one process after a warm-up
(medians): ``il.simulate(...)`` whole; the engine's entry (``run_from_python``) on
arrays prepared once, i.e. the kernel and Numba's dispatch of its arguments; the one
jitted call simulate() makes (``kernels.entry.simulate_run``: the run's setup, its
output array and the engine), its scalar arguments prepared; and the validation
(``check_run``) alone. The Python layer is the first minus the second.
Prints only; on a shared machine compare the figures of one run.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import impactlib as il  # noqa: E402
from impactlib.kernels import engine as E  # noqa: E402
from impactlib.kernels.entry import run_constants, section_times, simulate_run  # noqa: E402
from impactlib.model import RunLimits, check_run  # noqa: E402

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=5000)
    calls = ap.parse_args().calls
    p = PAPER
    sol = il.simulate(p, 500.0, t_record=250.0)
    limits = RunLimits()        # as simulate()'s default: made once
    sp, rate, hmax = run_constants(p.m, p.c, p.k, p.g, p.r, p.omega)
    ctl = E.controls(500.0, 250.0, hmax, rate, 0.0, 1e-6, 1e-9, limits.max_impacts,
                     limits.max_steps, E.EXACT, E.NO_TANGENT)
    pc_t = section_times(250.0, 500.0, 0.0, p.T)
    cap = 1024
    imp_t, imp_v = np.empty(cap), np.empty(cap)
    stick = np.empty((128, 2))
    pc_x, pc_v = np.empty(pc_t.size), np.empty(pc_t.size)
    none, none2, res = np.empty(0), np.empty((0, 2)), np.empty(E.NRES)
    max_impacts = float(limits.max_impacts)

    def kernel():
        E.run_from_python(sp, ctl, 0.0, 0.0, 0.0, imp_t, imp_v, stick, pc_t, pc_x, pc_v, none,
                          none, none, none, none2, res)

    runs = {
        "simulate()": lambda: il.simulate(p, 500.0, t_record=250.0),
        "engine entry, arrays prepared": kernel,
        "simulate_run, arguments prepared": lambda: simulate_run(
            p.m, p.c, p.k, p.g, p.r, p.omega, 0.0, 0.0, 0.0, 250.0, 500.0, 0.0, E.EXACT, 0.0,
            1e-6, 1e-9, max_impacts, limits.max_steps, none),
        "check_run": lambda: check_run(p, t_end=500.0, t_record=250.0, x0=None, v0=0.0,
                                       phase=0.0, method="exact", dt=None, rtol=1e-6,
                                       atol=1e-9, dense=0, limits=limits),
    }
    for fn in runs.values():
        for _ in range(100):
            fn()
    times = {k: [] for k in runs}
    for _ in range(calls):
        for k, fn in runs.items():
            tic = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - tic)
    med = {k: float(np.median(v)) for k, v in times.items()}
    assert int(res[E.N_TOT]) == sol.n_impacts      # the same run
    print(f"one exact 500 s trajectory at the paper defaults ({sol.n_impacts} impacts, "
          f"{sol.nsteps} steps), medians of {calls} calls:")
    for k, v in med.items():
        print(f"  {k}: {1e6 * v:.1f} µs")
    layer = med["simulate()"] - med["engine entry, arrays prepared"]
    print(f"  Python layer (simulate() minus the engine entry): {1e6 * layer:.1f} µs "
          f"({100 * layer / med['simulate()']:.0f}% of the call)")


if __name__ == "__main__":
    main()
