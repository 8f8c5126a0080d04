"""What ``il.classify`` calls the motion at each value of the diagram's sweep.

The Lyapunov strip marks chaos by this, not by the sign of λ₁ alone: classify says
"chaotic" only when the Poincaré points do not repeat and λ₁, measured over a window as
long as the run's own, exceeds twice its error; growing undamped motion is
"unbounded", a λ₁ within its error "undetermined". Each value is run as the diagram runs
it with independent starts (the same start, window and exact method), then classified.
A sweep with warm starts (up, down, both) starts each value where the previous one
ended; those starts are not kept, so such a strip is not classified.
"""
from __future__ import annotations

import collections
import threading

import numpy as np

import impactlib as il

from .diagram import DIAGRAM_MAX_IMPACTS_PER_500S, DIAGRAM_MAX_STEPS_PER_500S
from .state import Run

#: Finished classifications kept for later sessions (keyed by Run.diagram_key()).
CACHE_ITEMS = 32
_cache: collections.OrderedDict = collections.OrderedDict()
_lock = threading.Lock()


def classifiable(run: Run) -> bool:
    return run.bif_sweep == "independent"


def classify_value(run: Run, value: float) -> str:
    """``il.classify(...).kind`` of the diagram's run at ``value`` of ``run.bif_param``,
    within the diagram's own work ceilings; a run stopped at one (its λ₁ is NaN on the
    strip) is "undetermined"."""
    p = run.params.replace(**{run.bif_param: float(value)})
    scale = max(1.0, run.t_end / 500.0)
    limits = il.RunLimits(max_impacts=int(DIAGRAM_MAX_IMPACTS_PER_500S * scale),
                          max_steps=int(DIAGRAM_MAX_STEPS_PER_500S * scale))
    sol = il.simulate(p, t_end=run.t_end, t_record=run.t_record, x0=run.x0, v0=run.v0,
                      method="exact", limits=limits)
    return il.classify(sol).kind if sol.status == 0 else "undetermined"


def classify_values(run: Run, values: np.ndarray, live=lambda: True) -> list[str] | None:
    """Kinds for ``values`` (None if ``live()`` turned false before the end)."""
    key = (run.diagram_key(), tuple(np.asarray(values, dtype=float).tolist()))
    with _lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
    kinds = []
    for v in values:
        if not live():
            return None
        try:
            kinds.append(classify_value(run, v))
        except ValueError:               # the core refuses this value: no class
            kinds.append("undetermined")
    with _lock:
        _cache[key] = kinds
        while len(_cache) > CACHE_ITEMS:
            _cache.popitem(last=False)
    return kinds
