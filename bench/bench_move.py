"""Server CPU of one ω move in the explorer: the work a session's jobs do when omega
changes (scene with its Poincaré section, stability readout, the displacement view's
first zoom window), on values no cache holds, in one thread, after warm-up.

    .venv/bin/python bench/bench_move.py                 # this checkout's app
    APP_ROOT=/tmp/old .venv/bin/python bench/bench_move.py   # another app/ (same core)

Counts the simulations (il.simulate calls) and Lyapunov runs per move and reports the
median process CPU time per move (time.process_time: all threads of the process).
Prints only; figures from a shared machine are noisy: compare runs taken together.
"""
from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
if os.environ.get("APP_ROOT"):
    sys.path.insert(0, os.environ["APP_ROOT"])

import numpy as np  # noqa: E402
import impactlib as il  # noqa: E402
from impactlib.analysis import lyapunov as ly_module  # noqa: E402
from app import compute, stability, state  # noqa: E402

COUNTS = {"simulate": 0, "lyapunov": 0}
_sim, _ly = il.simulate, ly_module.lyapunov_run


def _count_sim(*a, **k):
    COUNTS["simulate"] += 1
    return _sim(*a, **k)


def _count_ly(*a, **k):
    COUNTS["lyapunov"] += 1
    return _ly(*a, **k)


il.simulate = _count_sim
ly_module.lyapunov_run = _count_ly


def run_at(omega: float) -> state.Run:
    return state.validate(state.parse_query({"omega": repr(omega)})[0])


def one_move(run: state.Run) -> None:
    """What the session's jobs compute for a new omega (explorer._apply, the views)."""
    scene, section = compute.scene_and_section(run, lambda: (None, None, None))
    stability.readout(run)
    start = max(run.t_record, run.t_end - 20 * run.params.T)
    compute.window_columns(run, start, run.t_end, 1000)


def main() -> None:
    print("app from", Path(compute.__file__).parent)
    one_move(run_at(1.9))                       # warm-up: compile, import
    # the slider's step is 0.01: distinct values 0.01 apart, none seen before
    for label, lo in (("periodic (ω = 1.92 ... 2.10)", 1.92), ("chaotic (ω = 2.81 ... 2.99)", 2.81)):
        cpu, counts = [], []
        for omega in lo + 0.01 * np.arange(19):
            run = run_at(round(float(omega), 2))
            COUNTS.update(simulate=0, lyapunov=0)
            c0 = time.process_time()
            one_move(run)
            cpu.append(time.process_time() - c0)
            counts.append((COUNTS["simulate"], COUNTS["lyapunov"]))
        sims = sorted({c[0] for c in counts})
        lys = sorted({c[1] for c in counts})
        print(f"{label}: median CPU {1e3 * statistics.median(cpu):.1f} ms per move "
              f"(min {1e3 * min(cpu):.1f}, max {1e3 * max(cpu):.1f}); simulations per move "
              f"{sims}, Lyapunov runs per move {lys}")


if __name__ == "__main__":
    main()
