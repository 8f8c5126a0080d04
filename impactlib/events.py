"""Impacts, sticking and release for the closed-form flight.

The next impact is the FIRST root of x(t) = g after the current time.  From a point s
with f = x - g >= 0, f' = v, f'' = a and a bound M3 >= |x'''| ahead (flight.derivative_bounds),
Taylor's theorem gives the lower bound

    f(s + tau) >= p(tau) = f + v tau + a tau^2 / 2 - M3 tau^3 / 6,

so no root lies before the first positive root of the cubic p.  Stepping to that root
never passes the wall, however shallow the dip; near a crossing the steps converge to it
from the left (cubically), near a miss they jump over the minimum once p clears it.
No fixed sampling step is involved.

Leaving the wall from rest where the force is exactly zero (release), f grows like
tau^3; the first step there uses the quartic bound with |x''''| <= M4.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit
from .flight import (C_, CPH, G, H0, HV0, K, M, OM, R, RES, SPH, T0, V0, W0SQ, X0,
                     derivative_bounds, flight_state, release_time, wall_force)

EPS = 2.220446049250313e-16
#: Longest certified step, in forcing periods.  At exact resonance the bound on the
#: secular term grows with the step, so the cap is shorter there.
HMAX_PERIODS = 0.5
HMAX_PERIODS_RESONANCE = 0.25



def step_caps(sps):
    """The step cap hmax of the impact search for each row of system constants ``sps``
    (one row, or an (n, NSP) array), in time units; :func:`step_cap` for one row in a kernel."""
    sps = np.asarray(sps)
    periods = np.where(sps[..., RES] != 0.0, HMAX_PERIODS_RESONANCE, HMAX_PERIODS)
    return periods * 2.0 * math.pi / sps[..., OM]


@jit
def step_cap(sp):
    periods = HMAX_PERIODS_RESONANCE if sp[RES] != 0.0 else HMAX_PERIODS
    return periods * 2.0 * math.pi / sp[OM]


# next_impact outcomes
NO_IMPACT, IMPACT, STEP_LIMIT = 0, 1, 2
# impact_outcome modes
FLY, STICK = 0, 1


@jit
def _lower_cubic(f, f1, f2, m3, tau):
    return f + tau * (f1 + tau * (0.5 * f2 - tau * m3 / 6.0))


@jit
def _bisect_cubic(f, f1, f2, m3, lo, hi):
    # p(lo) >= 0 > p(hi) on a stretch where p decreases; returns a point where p >= 0.
    # Illinois false position: superlinear, and it keeps the bracket.
    plo = _lower_cubic(f, f1, f2, m3, lo)
    phi = _lower_cubic(f, f1, f2, m3, hi)
    side = 0
    for _ in range(40):
        if hi - lo <= 1e-5 * hi:
            break
        den = plo - phi
        mid = (lo * (-phi) + hi * plo) / den if den > 0.0 else 0.5 * (lo + hi)
        if not (lo < mid < hi):
            mid = 0.5 * (lo + hi)
        pm = _lower_cubic(f, f1, f2, m3, mid)
        if pm > 0.0:
            lo, plo = mid, pm
            if side == 1:
                phi *= 0.5
            side = 1
        else:
            hi, phi = mid, pm
            if side == -1:
                plo *= 0.5
            side = -1
    return lo


@jit
def safe_step(f, f1, f2, m3, hmax):
    """Largest tau in [0, hmax] with p > 0 on (0, tau), p the cubic lower bound above.

    Returns 0 when p is not positive just after 0 (at the wall and moving or pushed in).
    """
    if m3 <= 0.0:
        m3 = 1e-300
    start = 0.0
    disc = f2 * f2 + 2.0 * m3 * f1
    if disc >= 0.0:
        sd = math.sqrt(disc)
        tm = (f2 - sd) / m3
        tp = (f2 + sd) / m3
        if tm > 0.0:
            hi = min(tm, hmax)
            if _lower_cubic(f, f1, f2, m3, hi) <= 0.0:
                return _bisect_cubic(f, f1, f2, m3, 0.0, hi)
            if hi == hmax:
                return hmax
            start = tp
        elif tp > 0.0:
            start = tp
    if start >= hmax:
        return hmax
    if _lower_cubic(f, f1, f2, m3, hmax) > 0.0:
        return hmax
    if start == 0.0 and f <= 0.0:
        return 0.0
    if start * m3 >= f2:
        # p is concave on [start, hmax]: Newton from the right end never passes the root
        x = hmax
        for _ in range(12):
            dp = f1 + x * (f2 - 0.5 * m3 * x)
            if dp >= 0.0:
                break
            x_new = x - _lower_cubic(f, f1, f2, m3, x) / dp
            if x_new >= x * (1.0 - 1e-7):
                x = x_new
                break
            x = x_new
        x *= 1.0 - 1e-6
        if start < x < hmax and _lower_cubic(f, f1, f2, m3, x) > 0.0:
            return x
    return _bisect_cubic(f, f1, f2, m3, start, hmax)


@jit
def _newton_in_bracket(sp, seg, lo, hi, flo, vlo, g, t0):
    """The root of f = x - g in [lo, hi], where f(lo) > 0 >= f(hi) and f decreases.

    Returns (s, v, evaluations).
    """
    s = lo - flo / vlo
    v = vlo
    n = 0
    for _ in range(60):
        if not (lo < s < hi):
            s = 0.5 * (lo + hi)
        x, v, a, j, rh, xs = flight_state(sp, seg, s)
        n += 1
        f = x - g
        if f > 0.0:
            lo = s
        else:
            hi = s
        step = -f / v if v < 0.0 else 0.5 * (lo + hi) - s
        if abs(step) <= 2.0 * EPS * (t0 + s) or hi - lo <= 2.0 * EPS * (t0 + s):
            s = min(max(s + step, lo), hi)
            break
        s = s + step
    return s, min(v, 0.0), n


@jit
def next_impact(sp, seg, s_end, hmax, max_steps):
    """First impact of a flight segment before s_end.

    Returns
    -------
    kind : int
        NO_IMPACT (reached s_end), IMPACT, or STEP_LIMIT.
    s : float
        Time into the segment of the impact (or where the search stopped).
    v : float
        Velocity just before the impact (<= 0).
    nsteps : int
        Closed-form evaluations spent.
    """
    g = sp[G]
    # the start state and its derivatives from Eq. (1) itself, without a closed-form call
    x = seg[X0]
    v = seg[V0]
    m = sp[M]
    a = (seg[CPH] - 2.0 * sp[C_] * v - sp[K] * x) / m
    j = (-sp[OM] * seg[SPH] - 2.0 * sp[C_] * a - sp[K] * v) / m
    rh = math.sqrt(seg[HV0] * seg[HV0] + sp[W0SQ] * seg[H0] * seg[H0])
    xs = abs(x)
    s = 0.0
    nsteps = 0
    if x - g <= 0.0 and v == 0.0:
        # at rest on the wall with a non-negative push: leave as tau^2 (a > 0) or tau^3 (a = 0)
        # the caller has decided the mass leaves (force >= 0); a < 0 here is rounding
        m3, m4 = derivative_bounds(sp, rh, min(hmax, s_end))
        tau = safe_step(0.0, 0.0, max(a, 0.0), m3, min(hmax, s_end))
        if j > 0.0:
            tau = max(tau, min(2.0 * j / m4, hmax, s_end))
        if tau <= 0.0:
            return IMPACT, 0.0, 0.0, nsteps
        s = tau
        if s >= s_end:
            return NO_IMPACT, s_end, v, nsteps
        x, v, a, j, rh, xs = flight_state(sp, seg, s)
        nsteps += 1
    t0 = abs(seg[T0])
    while True:
        f = x - g
        tol = 8.0 * EPS * (xs + abs(g))
        if f <= tol and (v < 0.0 or f < 0.0):
            # converged onto the crossing from the left: polish with Newton
            for _ in range(4):
                if v >= 0.0:
                    break
                ds = -(x - g) / v
                if abs(ds) > 1e-6 * hmax:
                    break
                s_new = min(max(s + ds, 0.0), s_end)
                x, v, a, j, rh, xs = flight_state(sp, seg, s_new)
                nsteps += 1
                done = abs(s_new - s) <= 4.0 * EPS * (t0 + s)
                s = s_new
                if done:
                    break
            return IMPACT, s, min(v, 0.0), nsteps
        h = min(hmax, s_end - s)
        m3, m4 = derivative_bounds(sp, rh, s + h)
        if v < 0.0:
            # v stays negative while its upper bound v + a tau + m3 tau^2 / 2 does, so f
            # decreases strictly there; if f's upper bound is <= 0 by then, the first
            # root is the only one in the bracket: finish with safeguarded Newton
            sq = math.sqrt(a * a - 2.0 * m3 * v)
            tv = -2.0 * v / (a + sq) if a >= 0.0 else (sq - a) / m3
            tv = min(tv, h)
            if f + tv * (v + tv * (0.5 * a + tv * m3 / 6.0)) <= 0.0:
                s, vh, ns = _newton_in_bracket(sp, seg, s, s + tv, x - g, v, g, t0)
                return IMPACT, s, vh, nsteps + ns
        tau = safe_step(max(f, 0.0), v, a, m3, h)
        if tau <= 4.0 * EPS * (t0 + s):
            # touching the wall at rest (tangency within rounding): a contact, v ~ 0
            return IMPACT, s, min(v, 0.0), nsteps
        if tau >= s_end - s:
            return NO_IMPACT, s_end, v, nsteps
        s += tau
        x, v, a, j, rh, xs = flight_state(sp, seg, s)
        nsteps += 1
        if nsteps > max_steps:
            return STEP_LIMIT, s, v, nsteps


@jit
def impact_outcome(sp, t, vplus, rate, tail_tol):
    """What follows an impact at time t with rebound velocity vplus = -r v(t-) >= 0.

    Returns (mode, t_next): FLY from t (vplus > 0, or at rest with the force pushing
    off), or STICK from t_next.  Once a rebound is so small that its hop lasts under
    tail_tol time scales, the rest of the chatter (infinitely many hops, rebounds
    vplus r^n) is summed, as in Budd & Dux (1994): each hop n satisfies
    int_hop A dt = v_n + v_{n+1} / r, with A = (k g - cos(omega t)) / m the push into the
    wall, so the sequence ends at t_inf with  int_t^t_inf A dt = 2 vplus / (1 - r).
    The mass sticks there, provided the push has not turned outwards by then.
    """
    r = sp[R]
    if vplus <= 0.0:
        tr = release_time(sp, t)
        if tr <= t:
            return FLY, t
        return STICK, t
    m = sp[M]
    a0 = -(wall_force(sp, t) - 2.0 * sp[C_] * vplus) / m
    if r < 1.0 and a0 > 0.0 and 2.0 * vplus * rate <= tail_tol * a0:
        target = 2.0 * vplus / (1.0 - r)
        om = sp[OM]
        kg = sp[K] * sp[G]
        tau = target / a0
        for _ in range(30):
            # int_t^{t+tau} A = (kg tau - (sin(om(t+tau)) - sin(om t)) / om) / m
            half = 0.5 * om * tau
            dsin = 2.0 * math.cos(om * t + half) * math.sin(half)
            gval = (kg * tau - dsin / om) / m - target
            a_end = (kg - math.cos(om * (t + tau))) / m
            if a_end <= 0.0:
                return FLY, t
            step = gval / a_end
            tau -= step
            if tau <= 0.0:
                return FLY, t
            if abs(step) <= 4.0 * EPS * (abs(t) + tau):
                break
        ts = t + tau
        if release_time(sp, t) > ts and wall_force(sp, ts) <= 0.0:
            return STICK, ts
    return FLY, t


@jit
def phase_of(t, om):
    """t mod T, T = 2 pi / omega, in [0, T)."""
    period = 2.0 * math.pi / om
    ph = t - period * math.floor(t / period)
    if ph >= period:
        ph -= period
    return ph


__all__ = ["safe_step", "next_impact", "impact_outcome", "phase_of", "step_caps", "step_cap", "OM"]
