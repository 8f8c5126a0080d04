"""The paper's (m, n) classification: m-impact period-n motion.

n is the smallest number of forcing periods after which the Poincare points repeat
(to a tolerance relative to the orbit's size), m the number of impacts in those n
periods.  A chatter summed to its accumulation point counts as infinitely many impacts
(complete chattering); no repeat within ``max_period`` periods means period infinity.

A motion without a period is called chaotic only when it earns it: :func:`classify`
measures the largest Lyapunov exponent (:mod:`impactlib.lyapunov`) and requires it to be
positive by more than twice its error estimate.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..kernels._jit import jit
from ..kernels.events import HMAX_PERIODS_RESONANCE
from .lyapunov import grows_without_bound, lyapunov_from, no_dissipation
from ..model import MotionCode, RunLimits

_INF = int(MotionCode.INFINITE)
_UNDETERMINED = int(MotionCode.UNDETERMINED)
_NOT_SETTLED = int(MotionCode.NOT_SETTLED)

PERIOD_RTOL = 1e-4    # transients of the paper's damping (c = 0.05) decay to ~1e-5 in 250 s
MAX_PERIOD = 32
CHAOS_SIGMAS = 2.0    # chaotic: largest exponent > CHAOS_SIGMAS x its error estimate
SETTLE_R2 = 0.8       # log-distance decay this well fitted by a line counts as settling


@jit
def motion_class(pc_x, pc_v, imp_t, t_end, period_T, n_chatter, rtol, max_period):
    """(m, n) from Poincare points and impact times in the window, with the codes of
    :class:`impactlib.model.MotionCode` (INFINITE, UNDETERMINED, NOT_SETTLED)."""
    npts = pc_x.shape[0]
    if npts < 4:
        return _UNDETERMINED, _UNDETERMINED     # window too short to tell
    scale = 1e-300
    for i in range(npts):
        scale = max(scale, abs(pc_x[i]), abs(pc_v[i]))
    tol = rtol * scale
    half = npts // 2
    n = _INF
    for cand in range(1, max_period + 1):
        if npts - half < 2 * cand:
            break
        ok = True
        for i in range(half, npts - cand):
            if abs(pc_x[i + cand] - pc_x[i]) > tol or abs(pc_v[i + cand] - pc_v[i]) > tol:
                ok = False
                break
        if ok:
            n = cand
            break
    if n < 0:
        # not periodic yet: a steady geometric decay of |P_{i+n} - P_i| is a transient
        # settling onto a period-n orbit (slow when a multiplier is near -1 or 1)
        for cand in range(1, max_period + 1):
            cnt = npts - cand - half
            if cnt < 8:
                break
            sx = 0.0
            sy = 0.0
            sxx = 0.0
            sxy = 0.0
            syy = 0.0
            for i in range(half, npts - cand):
                d = max(abs(pc_x[i + cand] - pc_x[i]), abs(pc_v[i + cand] - pc_v[i]))
                y = math.log(d + 1e-300)
                xi = float(i)
                sx += xi
                sy += y
                sxx += xi * xi
                sxy += xi * y
                syy += y * y
            vx = sxx - sx * sx / cnt
            vy = syy - sy * sy / cnt
            cxy = sxy - sx * sy / cnt
            if vx > 0.0 and vy > 0.0 and cxy < 0.0 and cxy * cxy / (vx * vy) >= SETTLE_R2:
                return _NOT_SETTLED, cand
        return (_INF if imp_t.shape[0] > 0 else 0), _INF
    if n_chatter > 0:
        return _INF, n
    t_from = t_end - n * period_T
    m = 0
    for i in range(imp_t.shape[0]):
        if imp_t[i] > t_from:
            m += 1
    return m, n


def _inf(v):
    return math.inf if v == MotionCode.INFINITE else v


@dataclass(frozen=True)
class Motion:
    impacts: float          # m: int, or math.inf
    period: float           # n: int, or math.inf
    kind: str               # "periodic", "complete chattering", "chaotic", "not settled",
                            # "no impact", "undetermined", "unbounded"
    label: str
    lyapunov: float = math.nan         # largest exponent measured (non-periodic motion)
    lyapunov_error: float = math.nan

    def __str__(self):
        return self.label


def describe(m: int, n: int) -> Motion:
    """Motion from the kernel's (m, n) codes (counts, or :class:`MotionCode`)."""
    if n == MotionCode.UNDETERMINED:
        return Motion(math.nan, math.nan, "undetermined",
                      "undetermined (record window shorter than 4 periods)")
    mi, ni = _inf(m), _inf(n)
    sym = lambda v: "∞" if v == math.inf else str(int(v))  # noqa: E731
    if m == MotionCode.NOT_SETTLED:
        return Motion(math.nan, math.nan, "not settled",
                      f"not settled (approaching period-{n}; lengthen the transient)")
    if m == 0:
        kind = "no impact"
        label = f"no impact (period-{sym(ni)})"
    elif n == MotionCode.INFINITE:
        kind = "chaotic"
        label = f"chaotic ({sym(mi)}-impact period-{sym(ni)})"
    elif m == MotionCode.INFINITE:
        kind = "complete chattering"
        label = f"complete chattering (∞-impact period-{sym(ni)})"
    else:
        kind = "periodic"
        label = f"{sym(mi)}-impact period-{sym(ni)}"
    return Motion(mi, ni, kind, label)


def lyapunov_budget(sol) -> RunLimits:
    """Work limits of the Lyapunov run that judges a solution's aperiodic motion: about
    the work of the solution itself, plus the certified walk's steps (at most a quarter
    period each) that the search falls back to near grazing."""
    window = sol.t_end - sol.t_record
    walk = 2 * math.ceil(window / (HMAX_PERIODS_RESONANCE * sol.params.T)) + 8 * sol.n_impacts
    return RunLimits(max_impacts=2 * sol.n_impacts + 1000,
                     max_steps=2 * sol.nsteps + walk + 10000)


def measure_lyapunov(sol):
    """Both Lyapunov exponents of the exact flow continued from where ``sol`` ends, over a
    window as long as its own, within :func:`lyapunov_budget`."""
    tf, xf, vf, stuck = sol.final
    window = sol.t_end - sol.t_record
    return lyapunov_from(sol.params, tf, xf, vf, tf + window, tf, limits=lyapunov_budget(sol))


def classify(sol, rtol: float = PERIOD_RTOL, max_period: int = MAX_PERIOD) -> Motion:
    """Classify a Solution as the paper does: (m impacts, period n) from its maps.

    A motion whose Poincare points do not repeat is measured before it is named: the
    largest Lyapunov exponent of the exact flow over a window as long as the solution's
    own, continued from where the solution ends.  "chaotic" needs it positive by more than
    CHAOS_SIGMAS times its error estimate; a negative one is a slow transient or a long
    period; one within its error says the window is too short.  Without dissipation
    (c = 0, r = 1) a motion whose impact speed keeps growing is "unbounded".  Runs by an
    integrator (rk4, rk45) are judged against the exact flow: if that contracts, the
    integrator's error is what kept the points from repeating.
    """
    return classify_measured(sol, rtol, max_period)[0]


def classify_measured(sol, rtol: float = PERIOD_RTOL, max_period: int = MAX_PERIOD):
    """(Motion, Lyapunov or None): :func:`classify` with the Lyapunov measurement it
    made (None where the maps decided alone), for callers that show the exponents."""
    m, n = motion_class(np.ascontiguousarray(sol.poincare.x), np.ascontiguousarray(sol.poincare.v),
                        np.ascontiguousarray(sol.impacts.t), sol.t_end, sol.params.T,
                        sol.n_chatter, rtol, max_period)
    return judge_motion(describe(m, n), sol, max_period)


def judge_motion(motion: Motion, sol, max_period: int = MAX_PERIOD, measured=None):
    """(Motion, Lyapunov or None): the verdict on ``motion``, the class the maps of
    ``sol`` give, measured where they find no period.  ``sol`` is a Solution, or any
    record of the same run with its params, method, t_record, t_end, final, n_impacts,
    nsteps and (read without dissipation only) impacts: a sweep that ran it judges from
    its own outputs instead of running it again.  ``measured`` is
    :func:`measure_lyapunov`'s result for ``sol`` where the caller has made it (a sweep
    measures its cells in one jitted loop)."""
    if motion.kind != "chaotic":
        return motion, None
    if no_dissipation(sol.params) and grows_without_bound(sol.impacts.t, sol.impacts.v,
                                                          sol.t_record, sol.t_end):
        return Motion(math.nan, math.nan, "unbounded",
                      "unbounded (no dissipation): the impact speed grows every cycle"), None
    ly = measure_lyapunov(sol) if measured is None else measured
    return _judged(sol, motion, ly, max_period), ly


def _judged(sol, motion, ly, max_period) -> Motion:
    """The verdict on an aperiodic motion from its Lyapunov measurement ``ly``."""
    window = sol.t_end - sol.t_record
    lam, err = float(ly.exponents[0]), float(ly.error[0])
    coarse = ""
    if sol.method != "exact":
        coarse = f"the {sol.method} run "
    if ly.unbounded:
        return Motion(math.nan, math.nan, "unbounded",
                      "unbounded (no dissipation): the impact speed grows every cycle")
    if ly.sticks:
        return Motion(math.nan, math.nan, "not settled",
                      "not settled (not periodic in the window, but the motion sticks to the "
                      "wall: Lyapunov exponents -inf; lengthen the transient)", lam, 0.0)
    if not math.isfinite(lam):
        return Motion(math.nan, math.nan, "undetermined",
                      f"undetermined (no Lyapunov exponent: {ly.message})")
    meas = f"λ1 = {lam:.3g} ± {err:.2g}"
    if lam > CHAOS_SIGMAS * err and not coarse:
        return dataclasses.replace(motion, lyapunov=lam, lyapunov_error=err)
    if coarse:
        if lam < -CHAOS_SIGMAS * err:
            return Motion(math.nan, math.nan, "undetermined",
                          f"undetermined ({coarse}is too coarse: its points do not repeat, "
                          f"but the exact flow here contracts, {meas}; use method='exact' "
                          "or a tighter tolerance)", lam, err)
        return Motion(math.nan, math.nan, "undetermined",
                      f"undetermined ({coarse}is not periodic; the exact flow here has "
                      f"{meas}; classify an exact run)", lam, err)
    if lam < -CHAOS_SIGMAS * err:
        return Motion(math.nan, math.nan, "not settled",
                      f"not settled (no period up to {max_period}, but contracting, {meas}: "
                      "a slow transient or a longer period)", lam, err)
    return Motion(math.nan, math.nan, "undetermined",
                  f"undetermined (not periodic; {meas} over a window of {window:g} time units is not "
                  "positive beyond its error: lengthen the window)", lam, err)

