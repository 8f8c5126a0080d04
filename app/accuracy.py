"""Accuracy readout: error against run time of exact, rk4 and rk45 for the current scene.

Computed on demand (a button), off the event loop. Impacts are matched by time with the
core's ``impactlib.verify.compare.match_impacts`` over the first ``HORIZON`` seconds from
τ = 0 (beyond that, in chaotic motion, any two solutions separate for reasons that are
not the method's). The yardstick is the exact method: the core's accuracy benchmark
checks it against an independent mpmath reference (errors <= 1e-11 on its cases);
that reference itself is not run here because for stiff or chattering settings it can
take minutes of pure-Python work, which a shared server cannot afford.
"""
from __future__ import annotations

import dataclasses
import html
import time

import numpy as np

import impactlib as il
from impactlib.verify.compare import V_FLOOR, match_impacts

from . import compute
from .settings import METHODS, method_options, method_text
from .state import Run

HORIZON = 40.0       # s of motion compared, from tau = 0
REPEATS = 3          # run time: median of this many runs of the whole scene
TIME_BUDGET = 1.0    # s spent on repeats per method at most


@dataclasses.dataclass(frozen=True)
class MethodResult:
    method: str
    setting: str
    seconds: float     # median run time of the whole scene run [0, t_end]
    compared: int      # impacts matched in [0, HORIZON]
    missed: int
    extra: int
    dt_max: float      # max |t_i - t_i(exact)|, s
    dv_rel: float      # max |v_i - v_i(exact)| / max |v(exact)|
    message: str


def _kwargs(run: Run, method: str, t_end: float) -> dict:
    x0, v0, _ = run.scene_start
    return dict(t_end=t_end, t_record=0.0, x0=x0, v0=v0, method=method,
                limits=compute.scene_limits(method), **method_options(run, method))


def _timed(run: Run, method: str) -> tuple[float, str]:
    kw = _kwargs(run, method, run.t_end)
    sol = il.simulate(run.params, **kw)          # warm-up
    times: list[float] = []
    while len(times) < REPEATS and sum(times) < TIME_BUDGET:
        tic = time.perf_counter()
        sol = il.simulate(run.params, **kw)
        times.append(time.perf_counter() - tic)
    return float(np.median(times)), ("" if sol.status == il.RunStatus.OK else str(sol.message))


def compare_methods(run: Run) -> list[MethodResult]:
    """Each method against the exact one over [0, HORIZON], and its scene run time."""
    horizon = min(run.t_end, HORIZON)
    ref = il.simulate(run.params, **_kwargs(run, "exact", horizon))
    ref_t, ref_v = np.asarray(ref.impacts.t), np.asarray(ref.impacts.v)
    scale = float(np.max(np.abs(ref_v))) if ref_v.size else 0.0
    out = []
    for method in METHODS:
        try:
            sol = il.simulate(run.params, **_kwargs(run, method, horizon))
            seconds, note = _timed(run, method)
        except ValueError as exc:           # e.g. rk4 beyond its stability limit
            out.append(MethodResult(method, method_text(run, method), np.nan, 0, 0, 0, np.nan,
                                    np.nan, str(exc)))
            continue
        t, v = np.asarray(sol.impacts.t), np.asarray(sol.impacts.v)
        pairs, missed, extra, _ = match_impacts(ref_t, ref_v, t, v, V_FLOOR * scale)
        if pairs:
            i, j = np.array(pairs).T
            dt_max = float(np.max(np.abs(t[j] - ref_t[i])))
            dv_rel = float(np.max(np.abs(v[j] - ref_v[i]))) / scale
        else:
            dt_max = dv_rel = np.nan
        out.append(MethodResult(method, method_text(run, method), seconds, len(pairs), missed,
                                extra, dt_max, dv_rel, note))
    return out


def to_html(results: list[MethodResult], horizon: float = HORIZON) -> str:
    def fmt(x, spec=".1e"):
        return "—" if not np.isfinite(x) else format(x, spec)

    rows = "".join(
        f"<tr><td>{r.method}</td><td>{html.escape(r.setting)}</td>"
        f"<td>{fmt(r.seconds * 1e3, '.3g')} ms</td><td>{r.compared}</td>"
        f"<td>{r.missed}/{r.extra}</td><td>{fmt(r.dt_max)}</td><td>{fmt(r.dv_rel)}</td>"
        f"<td>{html.escape(r.message)}</td></tr>" for r in results)
    return ("<table class='ie-accuracy'><tr><th>method</th><th>setting</th>"
            "<th>run time</th><th>impacts</th><th>missed/extra</th><th>max |Δτᵢ| (s)</th>"
            "<th>max |Δẋᵢ|/V</th><th></th></tr>" + rows + "</table>"
            f"<small>Impacts in the first {horizon:g} s from τ = 0, matched by time, "
            "against the exact method; run time: median of the whole scene run.</small>")
