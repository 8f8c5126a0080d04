"""Lyapunov exponents of the impact oscillator through its impacts.

The tangent matrix J follows the exact trajectory: between impacts J <- Phi(s) J (the
closed-form flow Jacobian), at an impact J <- S J (the saltation matrix), at a sticking
phase J <- 0 (see :mod:`impactlib.tangent`).  After every impact and at the edges of the
sub-windows J is re-orthonormalised, J = Q R, J <- Q, and log|R11|, log|R22| are summed
(Benettin et al., Meccanica 15 (1980) 9-20, with the impacts handled as in Müller 1995).
Over the record window [t_record, t_end] of length tau,

    lambda_i = (1 / tau) sum log|R_ii|,

and since log|R11| + log|R22| = log|det J| = 2 ln r (impact) - 2 alpha s (flight),
lambda_1 + lambda_2 = -2 c/m + 2 nu ln r exactly, nu the impacts per unit time.
A motion that sticks in the window has J = 0 there: both exponents are -inf.

The error estimate is the standard error of the exponents of ``windows`` equal
sub-windows of the record window (their spread divided by sqrt(windows)).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..kernels._jit import jit
from ..model import Params, RunLimits, RunStatus, check_run
from ..kernels import engine as E
from ..kernels.engine import Buffers
from ..simulate import run_constants

WINDOWS = 10
GROWTH = 1.25        # last quarter's largest |v| over the first's: unbounded (no dissipation)


@dataclass(frozen=True)
class Lyapunov:
    """Result of :func:`lyapunov`.

    exponents : (2,) per unit time, descending; -inf where the motion sticks; NaN where it
        grows without bound (no dissipation) or the run stopped early.
    error : (2,) standard error over the sub-windows (0 for -inf).
    n_impacts : impacts inside the record window.
    nu : impacts per unit time in the window.
    window : (t_record, t_end).
    sticks, unbounded : the two cases above.
    message : what the numbers mean or why they are missing.
    """

    params: Params
    exponents: np.ndarray
    error: np.ndarray
    n_impacts: int
    nu: float
    window: tuple
    sticks: bool
    unbounded: bool
    status: int
    message: str
    final: tuple


def no_dissipation(p: Params) -> bool:
    return p.c == 0.0 and p.r == 1.0


def grows_without_bound(imp_t, imp_v, t_lo, t_hi) -> bool:
    """Impact speeds rising from quarter to quarter of [t_lo, t_hi], the last quarter's
    largest above GROWTH times the first's: a motion gaining energy at every cycle (the
    undamped, elastic impact resonance), not a bounded one."""
    if imp_t.size < 8:
        return False
    edges = np.linspace(t_lo, t_hi, 5)
    peaks = []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = np.abs(imp_v[(imp_t >= a) & (imp_t < b)])
        if sel.size == 0:
            return False
        peaks.append(sel.max())
    return bool(np.all(np.diff(peaks) > 0) and peaks[-1] > GROWTH * peaks[0])


def lyapunov_run(p: Params, t0, x0, v0, t_end, t_record, windows=WINDOWS, keep_impacts=False,
                 limits: RunLimits = RunLimits()):
    """The kernel run behind :func:`lyapunov`, from time t0 (validated inputs)."""
    sp, rate, hmax = run_constants(p)
    marks = np.linspace(t_record, t_end, windows + 1)
    logs = np.zeros((windows, 2))
    cap = 0
    if keep_impacts or no_dissipation(p):
        cap = int(min(limits.max_impacts, 8 * ((t_end - t_record) / p.T + 2) + 1024))
    imp_t = np.empty(cap)
    imp_v = np.empty(cap)
    ctl = E.controls(t_end, t_record, hmax, rate, 0.0, 0.0, 0.0, limits.max_impacts,
                     limits.max_steps, E.EXACT, E.QR_MARKS)
    res = np.empty(E.NRES)
    status = E.run_engine(sp, ctl, t0, x0, v0,
                          E.buffers(imp_t=imp_t, imp_v=imp_v, marks=marks, logs=logs), res)
    if status == RunStatus.OUTPUT_FULL:
        # the impacts are a side output here (kept for the growth test, or not at all)
        status = RunStatus.OK
    k = min(int(res[E.N_REC]), cap)
    final = (float(res[E.T_F]), float(res[E.X_F]), float(res[E.V_F]), res[E.STUCK] != 0.0)
    return (logs, marks, status, res[E.STUCK_MARKED] != 0.0, int(res[E.N_MARKED]), imp_t[:k],
            imp_v[:k], final)


def lyapunov(p: Params, t_end: float = 5000.0, t_record: float = 500.0, x0: float | None = None,
             v0: float = 0.0, *, windows: int = WINDOWS) -> Lyapunov:
    """Both Lyapunov exponents of the motion from (x0, v0) at t = 0, over [t_record, t_end].

    Parameters
    ----------
    p : Params
    t_end, t_record : float
        End of the run and start of the averaging window (the transient before it is
        discarded, its tangent restarted at t_record).
    x0, v0 : float
        Initial state; x0 defaults to max(0, g).
    windows : int
        Sub-windows for the error estimate (>= 2).

    Returns
    -------
    Lyapunov
        ``exponents`` descending; -inf for both where the motion sticks in the window
        (its Jacobian vanishes); NaN where it grows without bound (c = 0, r = 1).
    """
    # no Poincare samples are kept, so the sample budget of check_run does not apply
    t_end, t_record, x0, v0, _, _, _, _ = check_run(
        p, t_end=t_end, t_record=t_record, x0=x0, v0=v0, phase=0.0, method="exact", dt=None,
        rtol=1e-6, atol=1e-9, dense=0, limits=RunLimits(max_samples=2 ** 62))
    if not t_record < t_end:
        raise ValueError(f"invalid run: t_record={t_record!r} must be < t_end={t_end!r} "
                         "(the exponents average over [t_record, t_end])")
    if isinstance(windows, bool) or not isinstance(windows, (int, np.integer)) or windows < 2:
        raise ValueError(f"windows={windows!r} must be a whole number >= 2")
    return lyapunov_from(p, 0.0, x0, v0, t_end, t_record, int(windows))


def lyapunov_from(p, t0, x0, v0, t_end, t_record, windows=WINDOWS,
                  limits: RunLimits = RunLimits()) -> Lyapunov:
    """:func:`lyapunov` from time t0 (inputs already validated), within ``limits``."""
    logs, marks, status, stuck, n_m, imp_t, imp_v, final = lyapunov_run(
        p, t0, x0, v0, t_end, t_record, windows, limits=limits)
    tau = t_end - t_record
    nu = n_m / tau
    unbounded = no_dissipation(p) and grows_without_bound(imp_t, imp_v, t_record, t_end)
    if stuck:
        exps = np.array([-math.inf, -math.inf])
        err = np.zeros(2)
        msg = "the motion sticks to the wall in the window: its Jacobian vanishes, exponents -inf"
    elif unbounded:
        exps = np.full(2, math.nan)
        err = np.full(2, math.nan)
        msg = "unbounded (no dissipation): the impact speed keeps growing; no exponents"
    elif status != RunStatus.OK:
        exps = np.full(2, math.nan)
        err = np.full(2, math.nan)
        msg = "the run stopped at a work limit before t_end; no exponents"
    else:
        total = logs.sum(axis=0) / tau
        sub = logs / np.diff(marks)[:, None]
        order = np.argsort(-total, kind="stable")
        exps = total[order]
        # an exponent of -inf (r = 0: every impact's saltation matrix is singular) has no
        # spread to estimate
        with np.errstate(invalid="ignore"):
            err = sub[:, order].std(axis=0, ddof=1) / math.sqrt(logs.shape[0])
        err = np.where(np.isfinite(exps), err, 0.0)
        msg = f"averaged over [{t_record:g}, {t_end:g}] ({n_m} impacts)"
    return Lyapunov(params=p, exponents=exps, error=err, n_impacts=int(n_m), nu=nu,
                    window=(t_record, t_end), sticks=stuck, unbounded=bool(unbounded),
                    status=RunStatus(int(status)), message=msg, final=final)


# ------------------------------------------------------------------ sweeps


@jit
def lyapunov_sweep_kernel(sps, x0s, v0, t_end, t_record, hmaxs, rates, out_t, out_v, counts,
                          status, finals, lyap, warm, max_impacts, max_steps):
    """sweeps.sweep_kernel (exact method, no classification) with the tangent carried
    along by the engine: lyap[i] = (sum log|R11|, sum log|R22|, stuck in window, impacts in window)
    of value i over its window [t0 + t_record, t0 + t_end]."""
    nvals = sps.shape[0]
    marks = np.empty(2)
    logs = np.zeros((1, 2))
    res = np.empty(E.NRES)
    none = np.empty(0)
    stick = np.empty((0, 2))
    x, v, t0 = x0s[0], v0, 0.0
    for i in range(nvals):
        sp = sps[i]
        om = sp[5]
        if not warm:
            x = x0s[i]
        elif i > 0:
            x = finals[i - 1, 1]
            v = finals[i - 1, 2]
            ph = sps[i - 1, 5] * finals[i - 1, 0]
            ph = ph - 2.0 * math.pi * math.floor(ph / (2.0 * math.pi))
            t0 = ph / om
        marks[0] = t0 + t_record
        marks[1] = t0 + t_end
        logs[0, 0] = 0.0
        logs[0, 1] = 0.0
        ctl = E.controls(t0 + t_end, t0 + t_record, hmaxs[i], rates[i], 0.0, 0.0, 0.0,
                         max_impacts, max_steps, E.EXACT, E.QR_MARKS)
        buf = Buffers(out_t[i], out_v[i], stick, none, none, none, none, none, none, marks,
                      logs)
        st = E.run_engine(sp, ctl, t0, x, v, buf, res)
        counts[i] = int(res[E.N_REC])
        status[i] = st
        finals[i, 0] = res[E.T_F]
        finals[i, 1] = res[E.X_F]
        finals[i, 2] = res[E.V_F]
        finals[i, 3] = res[E.STUCK]
        lyap[i, 0] = logs[0, 0]
        lyap[i, 1] = logs[0, 1]
        lyap[i, 2] = res[E.STUCK_MARKED]
        lyap[i, 3] = res[E.N_MARKED]


def largest_exponents(sps_c, sps_r, lyap, status, tau, out_t, out_v, counts, t_lo, t_hi):
    """The largest exponent per value from the sweep kernel's sums: -inf where the motion
    sticks in the window, NaN where it grows without bound or stopped at a work limit."""
    lam = np.maximum(lyap[:, 0], lyap[:, 1]) / tau
    lam = np.where(lyap[:, 2] > 0, -math.inf, lam)
    lam = np.where(status == RunStatus.IMPACT_LIMIT, math.nan, lam)
    lam = np.where(status == RunStatus.STEP_LIMIT, math.nan, lam)
    for i in np.flatnonzero((sps_c == 0.0) & (sps_r == 1.0)):
        k = min(counts[i], out_t.shape[1])
        if grows_without_bound(out_t[i, :k], out_v[i, :k], t_lo[i], t_hi[i]):
            lam[i] = math.nan
    return lam


def bifurcation_with_lyapunov(p, name, values, t_end, t_record, method, x0, v0, warm_start,
                              dt, rtol, atol, workers, cap_per_value, max_impacts, max_steps):
    """:func:`impactlib.bifurcation` with ``lyapunov=True``: the same runs (the exact
    kernels, the same scheduling) with the tangent carried along, so the diagram's rows
    come with the largest exponent of each value over the diagram's own window."""
    import time

    from ..sweeps import diagrams as sweeps

    if method != "exact":
        raise ValueError(f"lyapunov=True needs method='exact' (got method={method!r}): the "
                         "exponents come from the exact flow and saltation Jacobians")
    t_end, t_record, x0c, v0, _, dt, rtol, atol = sweeps._check_sweep(
        p, [name], t_end, t_record, x0, v0, method, dt, rtol, atol)
    values = sweeps._values_array(name, values)
    if warm_start not in (False, True, "up", "down", "both"):
        raise ValueError(f"warm_start={warm_start!r} must be False, 'up', 'down' or 'both'")
    if not t_record < t_end:
        raise ValueError(f"invalid sweep: t_record={t_record!r} must be < t_end={t_end!r} "
                         "for Lyapunov exponents over [t_record, t_end]")
    tic = time.perf_counter()
    ex = sweeps._executor(workers)
    n = values.size
    sps, hmaxs, rates = sweeps._param_rows(p, {name: values}, method, dt, x0)
    T_of = 2 * math.pi / sps[:, 5]
    if x0 is not None:
        x0s = np.full(n, x0c)
    elif name == "g":
        x0s = np.maximum(0.0, values)
    else:
        x0s = np.full(n, max(0.0, p.g))

    def run(order, warm):
        k = order.size
        out_t = np.empty((k, cap_per_value))
        out_v = np.empty((k, cap_per_value))
        counts = np.zeros(k, dtype=np.int64)
        status = np.zeros(k, dtype=np.int64)
        finals = np.zeros((k, 4))
        lyap = np.zeros((k, 4))
        lyapunov_sweep_kernel(sps[order], np.ascontiguousarray(x0s[order]), v0, t_end, t_record,
                              hmaxs[order], rates[order], out_t, out_v, counts, status, finals,
                              lyap, warm, max_impacts, max_steps)
        status = np.where((status == RunStatus.OK) & (counts > cap_per_value),
                          RunStatus.OUTPUT_FULL, status)
        t0 = finals[:, 0] - t_end
        lam = largest_exponents(sps[order, 1], sps[order, 4], lyap, status, t_end - t_record,
                                out_t, out_v, counts, t0 + t_record, t0 + t_end)
        return out_t, out_v, counts, status, lam

    jobs = []
    if warm_start:
        srt = np.argsort(values, kind="stable")
        for d in {"up": [1], True: [1], "down": [-1], "both": [1, -1]}[warm_start]:
            order = srt if d > 0 else srt[::-1]
            jobs.append((d, order, ex.submit(run, order, True)))
    else:
        nchunks = min(n, max(4 * (workers or sweeps.worker_count()), int(math.ceil(n / 128))))
        for j in range(nchunks):
            order = np.arange(j, n, nchunks)
            jobs.append((0, order, ex.submit(run, order, False)))
    parts = []
    lam_all = np.full(n, -math.inf)
    for d, order, fut in jobs:
        out_t, out_v, counts, st, lam = fut.result()
        parts.append((order, st, counts, sweeps._rows(values, order, T_of, out_t, out_v, counts, d)))
        # warm "both": the larger of the two directions' exponents (NaN if either is)
        lam_all[order] = np.maximum(lam_all[order], lam)
    bif = sweeps.merge_parts(name, values, parts, time.perf_counter() - tic)
    return dataclasses.replace(bif, lyapunov=lam_all)
