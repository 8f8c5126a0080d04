"""simulate(): one run of the impact oscillator, by the closed form or an integrator."""
from __future__ import annotations

import math
import time
import dataclasses
from dataclasses import dataclass

import numpy as np

from .kernels import engine as E
from .kernels._jit import jit
from .kernels.engine import METHOD_IDS
from .kernels.events import step_cap
from .kernels.flight import fastest_rate, system_constants
from .model import RUN_MESSAGES, Params, RunLimits, RunStatus, check_run
from .io.result import Result


# ---------------------------------------------------------------- Python layer


@dataclass(frozen=True)
class Impacts:
    t: np.ndarray
    phase: np.ndarray      # t mod T
    v: np.ndarray          # velocity just before impact, <= 0

    def __len__(self):
        return self.t.shape[0]

    def __getattr__(self, name):
        # simulate() leaves phase to be computed on first use, from t and the period
        d = self.__dict__
        if name == "phase" and "_period" in d:
            d["phase"] = np.mod(d["t"], d["_period"])
            return d["phase"]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


@dataclass(frozen=True)
class Samples:
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray

    def __len__(self):
        return self.t.shape[0]


@dataclass(frozen=True, repr=False, eq=False)
class Solution(Result):
    """Result of :func:`simulate` (fields read like scipy's OdeResult).

    Time is in the model's time units (s), x in length units, v in length per time unit.

    Attributes
    ----------
    params : Params
    method : str
        "exact", "rk4" or "rk45".
    t_end, t_record : float
        End of the run and start of the record window (s).
    phase : float
        Poincaré section: samples at t = phase + n T (s, in [0, T]).
    impacts : Impacts
        Impacts in [t_record, t_end]: ``t`` (s), ``phase`` = t mod T (s), ``v`` velocity just
        before impact (<= 0).
    poincare : Samples
        (t, x, v) on the section inside the window.
    sticking : ndarray, shape (k, 2)
        [start, release] times (s) of each interval at rest on the wall, clipped to the window.
    dense : Samples or None
        Samples (t, x, v) at the ``dense`` times (evenly spaced when ``dense`` is a
        number); None if not asked for.
    status : int
        0 reached t_end; 1 impact limit; 2 step limit; 3 output full (see ``message``).
    message : str
    final : tuple
        (t, x, v, stuck) where the run stopped.
    n_impacts : int
        All impacts, the transient included.
    n_chatter : int
        Chatter sequences in the window summed to their accumulation point.
    nsteps : int
        Search or integrator steps taken.
    elapsed : float
        Seconds in the kernel (not part of ``==``).
    options : dict
        The other settings of the run: x0, v0, t0 and dt (rk4) or rtol, atol (rk45).
    """

    params: Params
    method: str
    t_end: float
    t_record: float
    phase: float
    impacts: Impacts
    poincare: Samples
    sticking: np.ndarray
    dense: Samples | None
    status: int
    message: str
    final: tuple          # (t, x, v, stuck) where the run stopped
    n_impacts: int        # all impacts, including the transient
    n_chatter: int        # chatter sequences in the window summed to their accumulation point
    nsteps: int
    elapsed: float        # seconds in the kernel
    options: dict = dataclasses.field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.status == RunStatus.OK


@jit
def section_times(t_lo, t_hi, phase, period):
    """Poincare section times phase + n T inside [t_lo, t_hi] (a period's 1e-9 of slack
    at the ends, so a section on an end is kept despite rounding)."""
    n0 = math.ceil((t_lo - phase) / period - 1e-12)
    n1 = math.floor((t_hi - phase) / period + 1e-12)
    out = np.empty(max(0, n1 - n0 + 1))
    n = 0
    for i in range(out.shape[0]):
        t = phase + period * (n0 + i)
        if t_lo - 1e-9 * period <= t <= t_hi + 1e-9 * period:
            out[n] = t
            n += 1
    return out[:n]


@jit
def _run_constants(m, c, k, g, r, omega):
    sp = system_constants(m, c, k, g, r, omega)
    return sp, fastest_rate(sp), step_cap(sp)


@jit
def _run_setup(m, c, k, g, r, omega, t_lo, t_hi, phase, method, dt, rtol, atol, max_steps):
    # one kernel call for the constants, the run controls and the section times of a run
    sp, rate, hmax = _run_constants(m, c, k, g, r, omega)
    ctl = E.controls(t_hi, t_lo, hmax, rate, dt, rtol, atol, 0.0, max_steps, method,
                     E.NO_TANGENT)
    return sp, ctl, section_times(t_lo, t_hi, phase, 2.0 * math.pi / omega)


def run_constants(p: Params):
    """(sp, rate, hmax) of one run; sweeps.py builds the same for many rows at once."""
    return _run_constants(p.m, p.c, p.k, p.g, p.r, p.omega)


_NO_SAMPLES = np.empty(0)
_STATUS = {int(s): s for s in RunStatus}
_NO_LOGS = np.empty((0, 2))


def _built(cls, **fields):
    """An instance of the frozen dataclass ``cls`` from fields known to be complete and
    valid: one dict update instead of a frozen __init__'s setattr per field (a few µs of
    a simulate() call that takes tens)."""
    obj = object.__new__(cls)
    obj.__dict__.update(fields)
    return obj


def _options(method, x0, v0, t0, dt, rtol, atol) -> dict:
    out = {"x0": x0, "v0": v0, "t0": float(t0)}
    if method == "rk4":
        out["dt"] = dt
    elif method == "rk45":
        out.update(rtol=rtol, atol=atol)
    return out


def simulate(p: Params, t_end: float = 500.0, x0: float | None = None, v0: float = 0.0,
             t_record: float | None = None, phase: float = 0.0, method: str = "exact", *,
             dense: int = 0, dt: float | None = None, rtol: float = 1e-6, atol: float = 1e-9,
             t0: float = 0.0, max_impacts: int | None = None, max_steps: int | None = None,
             limits: RunLimits = RunLimits()) -> Solution:
    """Simulate Eq. (1) from (x0, v0) at t0 = 0 to t_end, keeping what lies in [t_record, t_end].

    Parameters
    ----------
    p : Params
    t_end, t_record : float
        End of the run and start of the record window; t_record defaults to t_end / 2
        (the paper: 500 and 250).
    x0, v0 : float
        Initial state; x0 defaults to max(0, g).
    phase : float
        Poincare section, in time units in [0, T]: samples at t = phase + n T.
    method : {"exact", "rk4", "rk45"}
        Closed form with guaranteed impact search, fixed-step RK4 (needs ``dt``), or
        adaptive Dormand-Prince (``rtol``, ``atol``).
    dense : int or array_like
        Number of evenly spaced samples of (x, v) on [t_record, t_end] (0 for none), or
        the sample times themselves: 1-D, ascending, inside [t_record, t_end].
    max_impacts, max_steps : int
        Work ceilings; reaching one ends the run with ``status`` > 0 and partial results.

    Returns
    -------
    Solution
    """
    t_end, t_record, x0, v0, phase, dt, rtol, atol = check_run(
        p, t_end=t_end, t_record=t_record, x0=x0, v0=v0, phase=phase, method=method, dt=dt,
        rtol=rtol, atol=atol, dense=dense, limits=limits)
    max_impacts = limits.max_impacts if max_impacts is None else int(max_impacts)
    max_steps = limits.max_steps if max_steps is None else int(max_steps)
    sp, ctl, pc_t = _run_setup(p.m, p.c, p.k, p.g, p.r, p.omega, t_record, t_end, phase,
                               METHOD_IDS[method], 0.0 if dt is None else dt, rtol, atol,
                               max_steps)
    res = np.empty(E.NRES)
    period = 2.0 * math.pi / p.omega
    if isinstance(dense, (int, np.integer)):
        d_t = np.linspace(t_record, t_end, dense) if dense else _NO_SAMPLES
    else:
        d_t = np.array(dense, dtype=float)
    n_pc, n_d = pc_t.shape[0], d_t.shape[0]
    n_periods = int((t_end - t_record) / period) + 2
    cap = min(max(1024, 8 * n_periods), max_impacts)
    while True:
        # one buffer for all outputs: impacts (t, v), sticking intervals, samples (x, v)
        buf = np.empty(2 * cap + 2 * (n_periods + 2) + 2 * (n_pc + n_d))
        imp_t, imp_v = buf[:cap], buf[cap:2 * cap]
        o = 2 * cap + 2 * (n_periods + 2)
        stick = buf[2 * cap:o].reshape(n_periods + 2, 2)
        samples = buf[o:]
        samples[:] = np.nan
        pc_x, pc_v = samples[:n_pc], samples[n_pc:2 * n_pc]
        d_x, d_v = samples[2 * n_pc:2 * n_pc + n_d], samples[2 * n_pc + n_d:]
        ctl[E.MAX_IMPACTS] = max_impacts
        tic = time.perf_counter()
        E.run_from_python(sp, ctl, float(t0), x0, v0, imp_t, imp_v, stick, pc_t, pc_x, pc_v,
                          d_t, d_x, d_v, _NO_SAMPLES, _NO_LOGS, res)
        elapsed = time.perf_counter() - tic
        n_rec = int(res[E.N_REC])
        # more impacts in the window than the arrays held: run again with room for all of
        # them, also when a work limit ended the run (its partial results must be complete)
        if n_rec > cap and cap < max_impacts:
            cap = min(max_impacts, max(2 * cap, n_rec))
            continue
        break
    out = res.tolist()          # Python numbers: one conversion, not one per field
    status = _STATUS[int(out[E.STATUS])]
    n_stick = int(out[E.N_STICK])
    tf, xf, vf, stuck = out[E.T_F], out[E.X_F], out[E.V_F], out[E.STUCK] != 0.0
    # the outputs are views of the one buffer (its size is bounded by the window)
    n_keep = min(n_rec, cap)
    it = imp_t[:n_keep]
    impacts = _built(Impacts, t=it, v=imp_v[:n_keep], _period=period)
    # samples are filled in time order: the kept ones are a prefix (a run stopped by a
    # work limit, or a section time a rounding past t_end, leaves the rest unfilled)
    k = n_pc - int(np.count_nonzero(np.isnan(pc_x)))
    poincare = _built(Samples, t=pc_t[:k], x=pc_x[:k], v=pc_v[:k])
    dense_out = None
    if d_t is not _NO_SAMPLES:
        k = n_d - int(np.count_nonzero(np.isnan(d_x)))
        dense_out = _built(Samples, t=d_t[:k], x=d_x[:k], v=d_v[:k])
    message = RUN_MESSAGES[status]
    if status == RunStatus.IMPACT_LIMIT or status == RunStatus.STEP_LIMIT:
        message += f" (stopped at t = {tf:.6g})"
    return _built(Solution, params=p, method=method, t_end=t_end, t_record=t_record, phase=phase,
                  impacts=impacts, poincare=poincare, sticking=stick[:n_stick],
                  dense=dense_out, status=status, message=message,
                  final=(tf, xf, vf, stuck),
                  n_impacts=int(out[E.N_TOT]), n_chatter=int(out[E.N_TAIL]),
                  nsteps=int(out[E.NSTEPS]), elapsed=elapsed,
                  options=_options(method, x0, v0, t0, dt, rtol, atol))
