"""simulate(): one run of the impact oscillator, by the closed form or an integrator."""
from __future__ import annotations

import math
import time
import dataclasses
from dataclasses import dataclass

import numpy as np

from .kernels import entry
from .kernels.engine import METHOD_IDS
from .kernels.entry import run_constants as _run_constants
from .model import RUN_MESSAGES, Params, RunLimits, RunStatus, check_plain_run, check_run
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


def run_constants(p: Params):
    """(sp, rate, hmax) of one run; sweeps.py builds the same for many rows at once."""
    return _run_constants(p.m, p.c, p.k, p.g, p.r, p.omega)


_NO_SAMPLES = np.empty(0)
_STATUS = {int(s): s for s in RunStatus}
_MESSAGES = {int(s): RUN_MESSAGES[s] for s in RunStatus}
_LIMITS = (int(RunStatus.IMPACT_LIMIT), int(RunStatus.STEP_LIMIT))


_new = object.__new__


def _built(cls, fields):
    """An instance of the frozen dataclass ``cls`` from fields known to be complete and
    valid: one dict update instead of a frozen __init__'s setattr per field (a few µs of
    a simulate() call that takes tens)."""
    obj = _new(cls)
    obj.__dict__.update(fields)
    return obj


def _samples(t, x, v):
    """:func:`_built` for Samples, its three stores written out (half the time of a dict
    built and copied, on a path that builds two or three per call)."""
    obj = _new(Samples)
    d = obj.__dict__
    d["t"] = t
    d["x"] = x
    d["v"] = v
    return obj


def _impacts(t, v, period):
    """:func:`_samples` for Impacts; ``phase`` is computed from ``_period`` on first use."""
    obj = _new(Impacts)
    d = obj.__dict__
    d["t"] = t
    d["v"] = v
    d["_period"] = period
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
    plain = (check_plain_run(p, t_end, t_record, x0, v0, phase, dense, limits)
             if method == "exact" else None)
    if plain is None:
        t_end, t_record, x0, v0, phase, dt, rtol, atol = check_run(
            p, t_end=t_end, t_record=t_record, x0=x0, v0=v0, phase=phase, method=method,
            dt=dt, rtol=rtol, atol=atol, dense=dense, limits=limits)
    else:
        t_end, t_record, x0, v0, phase = plain
    max_impacts = limits.max_impacts if max_impacts is None else int(max_impacts)
    max_steps = limits.max_steps if max_steps is None else int(max_steps)
    if max_impacts < 0:
        raise ValueError(f"invalid run: max_impacts={max_impacts!r} must be >= 0")
    if isinstance(dense, (int, np.integer)):
        d_t = np.linspace(t_record, t_end, dense) if dense else _NO_SAMPLES
    else:
        d_t = np.array(dense, dtype=float)
    tic = time.perf_counter()
    out, counts = entry.simulate_run(p.m, p.c, p.k, p.g, p.r, p.omega, float(t0), x0, v0,
                                     t_record, t_end, phase, METHOD_IDS[method],
                                     0.0 if dt is None else dt, rtol, atol,
                                     float(max_impacts), max_steps, d_t)
    elapsed = time.perf_counter() - tic
    (st, n_keep, cap, n_stick, n_stuck_max, n_pc, k_pc, k_d, tf, xf, vf, stuck, n_tot, n_tail,
     nsteps) = counts
    # the outputs are views of the one array (its size is bounded by the window)
    o_pc = 2 * (cap + n_stuck_max)
    message = _MESSAGES[st]
    if st in _LIMITS:
        message += f" (stopped at t = {tf:.6g})"
    if d_t is _NO_SAMPLES:
        dense_out = None
    else:
        o_d = o_pc + 3 * n_pc
        n_d = d_t.shape[0]
        dense_out = _samples(d_t[:k_d], out[o_d:o_d + k_d], out[o_d + n_d:o_d + n_d + k_d])
    return _built(Solution, {
        "params": p, "method": method, "t_end": t_end, "t_record": t_record, "phase": phase,
        "impacts": _impacts(out[:n_keep], out[cap:cap + n_keep], 2.0 * math.pi / p.omega),
        "poincare": _samples(out[o_pc:o_pc + k_pc], out[o_pc + n_pc:o_pc + n_pc + k_pc],
                             out[o_pc + 2 * n_pc:o_pc + 2 * n_pc + k_pc]),
        "sticking": out[2 * cap:2 * cap + 2 * n_stick].reshape(n_stick, 2),
        "dense": dense_out, "status": _STATUS[st], "message": message,
        "final": (tf, xf, vf, stuck), "n_impacts": n_tot, "n_chatter": n_tail,
        "nsteps": nsteps, "elapsed": elapsed,
        "options": _options(method, x0, v0, t0, dt, rtol, atol)})
