"""Accuracy readout: each method against the exact solution, with its run time.

Computed on demand (a button), off the event loop. Errors are measured on the first
``N_IMPACTS`` impacts from τ = 0, matched by index: far beyond that, in chaotic motion,
any two solutions separate for reasons that are not the method's.
"""
from __future__ import annotations

import dataclasses
import html
import time

import numpy as np

import impactlib as il

from . import compute
from .compute import run_simulate
from .state import METHODS, Run

N_IMPACTS = 50
WALL_TIME = 5.0


@dataclasses.dataclass(frozen=True)
class MethodResult:
    method: str
    setting: str
    seconds: float
    impacts: int
    dt_max: float      # max |t_i - t_i(exact)| over the compared impacts, s
    dv_max: float      # max |v_i - v_i(exact)| over the compared impacts
    compared: int
    message: str


def _run(run: Run, method: str):
    kw = dict(t_end=run.t_end, t_record=0.0, x0=run.x0, v0=run.v0, method=method,
              wall_time=WALL_TIME,
              limits=il.RunLimits(max_impacts=compute.SCENE_MAX_IMPACTS,
                                  max_steps=compute.SCENE_MAX_STEPS[method],
                                  max_samples=compute.SCENE_MAX_SAMPLES))
    if method == "rk4":
        kw["dt"] = run.dt
    elif method == "rk45":
        kw.update(rtol=run.rtol, atol=run.atol)
    t0 = time.perf_counter()
    sol = run_simulate(run.params, **kw)
    return sol, time.perf_counter() - t0


def compare_methods(run: Run) -> list[MethodResult]:
    """Run exact, rk4 and rk45 over [0, t_end] and compare their impacts with exact."""
    exact, _ = _run(run, "exact")
    exact, t_exact = _run(run, "exact")       # second call: JIT and caches warm
    te, ve = np.asarray(exact.impacts.t), np.asarray(exact.impacts.v)
    out = []
    for method in METHODS:
        if method == "exact":
            sol, seconds = exact, t_exact
        else:
            try:
                sol, seconds = _run(run, method)
            except ValueError as exc:
                out.append(MethodResult(method, "", float("nan"), 0, float("nan"),
                                        float("nan"), 0, str(exc)))
                continue
        t, v = np.asarray(sol.impacts.t), np.asarray(sol.impacts.v)
        n = min(N_IMPACTS, t.size, te.size)
        dt_max = float(np.max(np.abs(t[:n] - te[:n]))) if n else float("nan")
        dv_max = float(np.max(np.abs(v[:n] - ve[:n]))) if n else float("nan")
        setting = {"exact": "closed form", "rk4": f"dt = {run.dt:g}",
                   "rk45": f"rtol = {run.rtol:g}, atol = {run.atol:g}"}[method]
        msg = "" if sol.status == 0 else str(sol.message)
        out.append(MethodResult(method, setting, seconds, int(t.size), dt_max, dv_max, n,
                                msg))
    return out


def to_html(results: list[MethodResult]) -> str:
    rows = []
    for r in results:
        def fmt(x, unit=""):
            return "—" if not np.isfinite(x) else f"{x:.2e}{unit}"
        rows.append(f"<tr><td>{r.method}</td><td>{r.setting}</td>"
                    f"<td>{fmt(r.seconds * 1e3)} ms</td><td>{r.impacts}</td>"
                    f"<td>{fmt(r.dt_max)}</td><td>{fmt(r.dv_max)}</td>"
                    f"<td>{html.escape(r.message)}</td></tr>")
    return ("<table class='ie-accuracy'><tr><th>method</th><th>setting</th><th>run time</th>"
            "<th>impacts</th><th>max |Δτ_I|</th><th>max |Δẋ_I|</th><th></th></tr>"
            + "".join(rows) + f"</table><small>Errors over the first {N_IMPACTS} impacts "
            "from τ = 0, against the exact method; run time of the whole run.</small>")
