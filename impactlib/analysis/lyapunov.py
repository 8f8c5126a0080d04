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

import math
from dataclasses import dataclass

import numpy as np

from ..model import Params, RunLimits, RunStatus, check_run
from ..kernels import engine as E
from ..kernels._jit import jit
from ..kernels.entry import run_constants as entry_run_constants
from ..simulate import run_constants
from ..io.result import Result

WINDOWS = 10
GROWTH = 1.25        # last quarter's largest |v| over the first's: unbounded (no dissipation)


@dataclass(frozen=True, repr=False, eq=False)
class Lyapunov(Result):
    """Result of :func:`lyapunov` (exponents and errors in 1/s, times in s).

    Attributes
    ----------
    params : Params
    exponents : ndarray, shape (2,)
        Per unit time, descending; -inf where the motion sticks; NaN where it grows
        without bound (no dissipation) or the run stopped early.
    error : ndarray, shape (2,)
        Standard error over the sub-windows (0 for -inf).
    n_impacts : int
        Impacts inside the record window.
    nu : float
        Impacts per unit time in the window.
    window : tuple
        (t_record, t_end).
    sticks, unbounded : bool
        The two cases above.
    status : int
        The run's status (as :class:`impactlib.Solution`).
    message : str
        What the numbers mean or why they are missing.
    final : tuple
        (t, x, v, stuck) where the run stopped.
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
    return lyapunov_result(p, t_end, t_record, logs, marks, status, stuck, n_m, imp_t, imp_v,
                           final)


def lyapunov_result(p, t_end, t_record, logs, marks, status, stuck, n_m, imp_t, imp_v,
                    final) -> Lyapunov:
    """The :class:`Lyapunov` result of a run's outputs (:func:`lyapunov_run`'s)."""
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


@jit
def lyapunov_rows(rows, starts, t_ends, t_records, limits, marks, logs, out):
    """:func:`lyapunov_run` for many runs in one jitted loop, impacts not kept: run i of
    the parameters rows[i] = (m, c, k, g, r, omega) from starts[i] = (t0, x0, v0) over
    [t_records[i], t_ends[i]] within limits[i] = (max_impacts, max_steps), with the marks
    marks[i] (windows + 1); fills logs[i] (windows, 2) and out[i] = (status, stuck in the
    window, impacts in it, t, x, v, stuck at the end)."""
    none = np.empty(0)
    stick = np.empty((0, 2))
    res = np.empty(E.NRES)
    for i in range(rows.shape[0]):
        sp, rate, hmax = entry_run_constants(rows[i, 0], rows[i, 1], rows[i, 2], rows[i, 3],
                                             rows[i, 4], rows[i, 5])
        ctl = E.controls(t_ends[i], t_records[i], hmax, rate, 0.0, 0.0, 0.0, limits[i, 0],
                         limits[i, 1], E.EXACT, E.QR_MARKS)
        status = E.run_engine(sp, ctl, starts[i, 0], starts[i, 1], starts[i, 2],
                              E.Buffers(none, none, stick, none, none, none, none, none, none,
                                        marks[i], logs[i]), res)
        out[i, 0] = status
        out[i, 1] = res[E.STUCK_MARKED]
        out[i, 2] = res[E.N_MARKED]
        out[i, 3] = res[E.T_F]
        out[i, 4] = res[E.X_F]
        out[i, 5] = res[E.V_F]
        out[i, 6] = res[E.STUCK]
