"""Server CPU of one ω move in the explorer: the work a session's jobs do when omega
changes (scene with its Poincaré section, stability readout, the time plot's first
window), on values no cache holds, in one thread, after warm-up.

    .venv/bin/python bench/bench_move.py                 # this checkout's app
    APP_ROOT=/tmp/old .venv/bin/python bench/bench_move.py   # another app/ (same core)
    BEFORE=/tmp/old/app .venv/bin/python bench/bench_move.py  # both, in one process

Counts the simulations (il.simulate calls) and Lyapunov runs per move and reports the
median process CPU time per move (time.process_time: all threads of the process).
With BEFORE (another checkout's app/ folder, loaded as the package ``app_before``) the
two apps' moves alternate in one process, this app on every other value of the range
and the other app on the values between (the apps' caches may share keys, and the
settings round omega to the slider's step), and the ratio of their medians is printed: on a shared machine only
such a ratio is worth comparing. Prints only.
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

import importlib.util  # noqa: E402

import numpy as np  # noqa: E402
import impactlib as il  # noqa: E402
from impactlib.analysis import lyapunov as ly_module  # noqa: E402
import app  # noqa: E402

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


def load_before(folder: str):
    """Another checkout's app package, importable beside this one as ``app_before``."""
    spec = importlib.util.spec_from_file_location(
        "app_before", Path(folder) / "__init__.py", submodule_search_locations=[folder])
    module = importlib.util.module_from_spec(spec)
    sys.modules["app_before"] = module
    spec.loader.exec_module(module)
    return module


def mover(package):
    """one_move(omega) of ``package``'s app: what the session's jobs compute for a new
    omega (explorer._apply, the views)."""
    compute = importlib.import_module(package.__name__ + ".compute")
    stability = importlib.import_module(package.__name__ + ".stability")
    state = importlib.import_module(package.__name__ + ".state")

    def one_move(omega: float) -> None:
        run = state.validate(state.parse_query({"omega": repr(omega)})[0])
        compute.scene_and_section(run, lambda: (None, None, None))
        stability.readout(run)
        # the time plot's first window: the last 8 periods, a plot 1000 px wide
        start = max(run.t_record, run.t_end - 8 * run.params.T)
        compute.window_columns(run, start, run.t_end, 1000)

    one_move.source = Path(compute.__file__).parent
    return one_move


def main() -> None:
    movers = {"this": mover(app)}
    if os.environ.get("BEFORE"):
        movers["before"] = mover(load_before(os.environ["BEFORE"]))
    for name, move in movers.items():
        print(f"{name}: app from {move.source}")
        move(1.9)                       # warm-up: compile, import
    # the slider's step is 0.01: distinct values 0.01 apart, none seen before
    for label, lo in (("periodic (from ω = 1.92)", 1.92), ("chaotic (from ω = 2.81)", 2.81)):
        cpu = {name: [] for name in movers}
        counts = {name: [] for name in movers}
        for i, omega in enumerate(lo + 0.01 * len(movers) * np.arange(19)):
            # which app goes first alternates (the second finds the first's data warm)
            for k, (name, move) in sorted(enumerate(movers.items()), reverse=i % 2 == 1):
                COUNTS.update(simulate=0, lyapunov=0)
                c0 = time.process_time()
                move(round(float(omega) + 0.01 * k, 2))
                cpu[name].append(time.process_time() - c0)
                counts[name].append((COUNTS["simulate"], COUNTS["lyapunov"]))
        print(label)
        for name in movers:
            sims = sorted({c[0] for c in counts[name]})
            lys = sorted({c[1] for c in counts[name]})
            c = cpu[name]
            print(f"  {name}: median CPU {1e3 * statistics.median(c):.2f} ms per move "
                  f"(min {1e3 * min(c):.2f}, max {1e3 * max(c):.2f}); simulations per move "
                  f"{sims}, Lyapunov runs per move {lys}")
        if len(movers) == 2:
            print(f"  this / before: {statistics.median(cpu['this']) / statistics.median(cpu['before']):.2f}")


if __name__ == "__main__":
    main()
