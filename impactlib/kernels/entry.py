"""The entry of a whole simulate() run from Python: one jitted call from the parameters
and the settings as scalars to the filled outputs.

Every call from Python pays Numba's dispatch (microseconds, more for each array
argument) and every array made in Python a few more; so the run's constants, controls,
section times and output array are made here, the retry for a window holding more
impacts than the first guess is taken here, and the outcome comes back as one float
array (the outputs, laid out in :func:`simulate_run`'s docstring) and a tuple of counts
and the final state.
"""
from __future__ import annotations

import math

import numpy as np

from . import engine as E
from ._jit import jit
from .events import step_cap
from .flight import fastest_rate, system_constants


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
def run_constants(m, c, k, g, r, omega):
    """(sp, rate, hmax) of one run: the system constants, the fastest rate and the search's
    step cap."""
    sp = system_constants(m, c, k, g, r, omega)
    return sp, fastest_rate(sp), step_cap(sp)


@jit
def _unfilled(a):
    n = 0
    for i in range(a.shape[0]):
        if math.isnan(a[i]):
            n += 1
    return n


@jit
def simulate_run(m, c, k, g, r, omega, t0, x0, v0, t_record, t_end, phase, method, dt, rtol,
                 atol, max_impacts, max_steps, d_t):
    """One run of :func:`impactlib.simulate` from (x0, v0) at t0 to t_end.

    ``method`` is a code of :data:`impactlib.kernels.engine.METHOD_IDS`; ``max_impacts``
    is a float (the controls hold floats), ``max_steps`` an int; ``d_t`` the sorted dense
    sample times (empty for none).

    Returns ``(out, counts)``. ``out`` (float64) holds, one after the other: the impact
    times and velocities (``cap`` each), the sticking intervals (``n_stuck_max`` rows of
    2), the section times, x and v (``n_pc`` each), the dense x and v (``len(d_t)``
    each); ``counts`` is ``(status, n_keep, cap, n_stick, n_stuck_max, n_pc, k_pc, k_d,
    t_f, x_f, v_f, stuck, n_tot, n_tail, nsteps)``: the impacts kept of those in the
    window, the samples filled (a prefix of each list: samples are filled in time order,
    and a run stopped by a work limit or a section time a rounding past t_end leaves the
    rest), the final state, all impacts, the chatter sequences summed in the window and
    the steps taken.
    """
    sp, rate, hmax = run_constants(m, c, k, g, r, omega)
    ctl = E.controls(t_end, t_record, hmax, rate, dt, rtol, atol, max_impacts, max_steps,
                     method, E.NO_TANGENT)
    period = 2.0 * math.pi / omega
    pc_t = section_times(t_record, t_end, phase, period)
    n_pc = pc_t.shape[0]
    n_d = d_t.shape[0]
    n_periods = int((t_end - t_record) / period) + 2
    n_stuck_max = n_periods + 2
    cap = int(min(max(1024.0, 8.0 * n_periods), max_impacts))
    res = np.empty(E.NRES)
    marks = np.empty(0)
    logs = np.empty((0, 2))
    while True:
        o_st = 2 * cap
        o_pc = o_st + 2 * n_stuck_max
        o_d = o_pc + 3 * n_pc
        out = np.empty(o_d + 2 * n_d)
        out[o_pc:o_pc + n_pc] = pc_t
        out[o_pc + n_pc:] = np.nan
        pc_x, pc_v = out[o_pc + n_pc:o_pc + 2 * n_pc], out[o_pc + 2 * n_pc:o_d]
        d_x, d_v = out[o_d:o_d + n_d], out[o_d + n_d:]
        buf = E.Buffers(out[:cap], out[cap:o_st], out[o_st:o_pc].reshape(n_stuck_max, 2),
                        pc_t, pc_x, pc_v, d_t, d_x, d_v, marks, logs)
        E.run_engine(sp, ctl, t0, x0, v0, buf, res)
        n_rec = int(res[E.N_REC])
        # more impacts in the window than the arrays held: run again with room for all of
        # them, also when a work limit ended the run (its partial results must be complete)
        if n_rec > cap and cap < max_impacts:
            cap = int(min(max_impacts, max(2 * cap, n_rec)))
            continue
        break
    counts = (int(res[E.STATUS]), min(n_rec, cap), cap, int(res[E.N_STICK]), n_stuck_max,
              n_pc, n_pc - _unfilled(pc_x), n_d - _unfilled(d_x), res[E.T_F], res[E.X_F],
              res[E.V_F], res[E.STUCK] != 0.0, int(res[E.N_TOT]), int(res[E.N_TAIL]),
              int(res[E.NSTEPS]))
    return out, counts
