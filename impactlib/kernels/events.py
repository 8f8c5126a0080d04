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

from ._jit import jit, with_item
from .flight import (ALPHA, C_, CPH, FA, G, H0, HV0, K, M, OM, RES, SPH, T0, V0, W0SQ, X0,
                     derivative_bounds, flight_state, motion_bounds)

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
        m3, m4 = derivative_bounds(sp, rh, min(hmax, s_end), x, v, min(hmax, s_end))
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
    return search_from(sp, seg, s, x, v, a, rh, xs, s_end, hmax, max_steps, nsteps)


@jit
def search_from(sp, seg, s, x, v, a, rh, xs, s_end, hmax, max_steps, nsteps):
    """The certified first-root search of :func:`next_impact`, from the state (x, v, a)
    at s into the segment (x - g >= 0 there, or converged onto the wall), up to s_end.

    rh and xs are flight_state's energy bound and size of x at s; nsteps counts the
    evaluations spent so far.  Returns as next_impact.
    """
    g = sp[G]
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
        m3, m4 = derivative_bounds(sp, rh, s + h, x, v, h)
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
        if tau >= s_end - s:
            # clear of the wall up to s_end; tested first, since a remainder s_end - s
            # at rounding level gives a step at rounding level that is no contact
            return NO_IMPACT, s_end, v, nsteps
        if tau <= 4.0 * EPS * (t0 + s):
            # touching the wall at rest (tangency within rounding): a contact, v ~ 0
            return IMPACT, s, min(v, 0.0), nsteps
        s += tau
        x, v, a, j, rh, xs = flight_state(sp, seg, s)
        nsteps += 1
        if nsteps > max_steps:
            return STEP_LIMIT, s, v, nsteps


# ------------------------------------------------------------ short hops

#: degree of the Taylor polynomial of a short hop (short_hop)
SHORT_HOP_ORDER = 8
_ZEROS = (0.0,) * (SHORT_HOP_ORDER + 1)


@jit
def short_hop(sp, seg, s_end):
    """A short hop from the wall (chatter), from the Taylor polynomial of x at its start.

    The derivatives of x at the start follow from Eq. (1) itself (x'' = (cos(omega t) -
    2 c x' - k x) / m, differentiated), no closed-form evaluation; the remainder after
    degree N = SHORT_HOP_ORDER is at most R tau^(N+1), R = M / (N+1)!, M bounding
    |x^(N+1)| (the smaller of the two bounds of flight.derivative_bounds, to order N+1).
    f = x - g lies between p - R tau^(N+1) and p + R tau^(N+1), p the polynomial; the
    lower one is shown positive before its first root tau_lo (Bernstein coefficients of
    (p - R tau^(N+1)) / tau on [0, tau_lo]), so no earlier root; the upper one's root
    tau_hi bounds the root from above.  The hop is accepted only when tau_hi - tau_lo and
    the velocity's remainder are at rounding level.

    Returns (ok, s, v): the impact time into the segment and the velocity before it;
    ok False (nothing decided) for a start not on the wall, a hop that is not short
    enough, or exact resonance.
    """
    g = sp[G]
    x0 = seg[X0]
    u = seg[V0]
    if x0 != g or not u > 0.0 or sp[RES] != 0.0:
        return False, 0.0, 0.0
    m, c, k, om = sp[M], sp[C_], sp[K], sp[OM]
    n = SHORT_HOP_ORDER
    cph, sph = seg[CPH], seg[SPH]
    acc = (cph - 2.0 * c * u - k * x0) / m
    if not acc < 0.0:
        return False, 0.0, 0.0
    alpha, w0sq = sp[ALPHA], sp[W0SQ]
    tau = 2.0 * u / -acc
    if tau * max(om, 2.0 * alpha + math.sqrt(w0sq)) > 0.5:
        # the remainder's terms (lambda tau)^(n+1) / (n+1)! exceed rounding by far
        return False, 0.0, 0.0
    # remainder bound: homogeneous derivatives b_j plus forcing FA omega^j, or the
    # energy bound over the hop (span: the parabola's root with a margin; a root found
    # beyond it is refused below)
    rh = math.sqrt(seg[HV0] * seg[HV0] + w0sq * seg[H0] * seg[H0])
    b_prev = rh
    b = rh * (2.0 * alpha + math.sqrt(w0sq))
    fact = 2.0
    for j in range(3, n + 2):
        b_prev, b = b, 2.0 * alpha * b + w0sq * b_prev
        fact *= j
    span = 2.0 * tau
    rem = min(b + sp[FA] * om ** (n + 1), motion_bounds(sp, x0, u, span, n + 1)[1]) / fact
    # can the remainder fix the parabola's root to rounding (it moves the root by about
    # rem tau^(n+1) / u)?
    if not (tau < s_end and rem * tau ** (n + 1) <= 4.0 * EPS * u * (abs(seg[T0]) + tau)):
        return False, 0.0, 0.0
    # Taylor coefficients a[j] = x^(j) / j! of f at the start (a[0] = 0)
    # coefficients in tuples (with_item): no array allocated per hop
    e = with_item(with_item(_ZEROS, 0, x0), 1, u)
    fj = 1.0
    for j in range(n - 1):
        # j-th derivative of cos(omega t): omega^j (cos, -sin, -cos, sin)[j mod 4]
        r4 = j % 4
        trig = cph if r4 == 0 else (-sph if r4 == 1 else (-cph if r4 == 2 else sph))
        e = with_item(e, j + 2, (fj * trig - 2.0 * c * e[j + 1] - k * e[j]) / m)
        fj *= om
    if not e[2] < 0.0:
        return False, 0.0, 0.0
    a = _ZEROS
    fj = 1.0
    for j in range(1, n + 1):
        fj *= j
        a = with_item(a, j, e[j] / fj)
    # tau_lo: Newton on q(tau) = (p - rem tau^(n+1)) / tau from the parabola's root
    tau_lo = tau_hi = 0.0
    for sign in (-1.0, 1.0):
        for _ in range(30):
            q = sign * rem
            dq = 0.0
            for j in range(n, 0, -1):
                dq = dq * tau + q
                q = q * tau + a[j]
            # q = sum a_j tau^(j-1) + sign rem tau^n, dq its derivative
            if not dq < 0.0:
                return False, 0.0, 0.0
            step = q / dq
            tau -= step
            if not (0.0 < tau < s_end):
                return False, 0.0, 0.0
            if abs(step) <= EPS * tau:
                break
        if sign < 0.0:
            tau_lo = tau * (1.0 - 4.0 * EPS)
        else:
            tau_hi = tau * (1.0 + 4.0 * EPS)
    if tau_hi - tau_lo > 2.0 * EPS * (abs(seg[T0]) + tau_lo) or tau_hi > span:
        return False, 0.0, 0.0
    # no earlier root: Bernstein coefficients of q_lo on [0, tau_lo] all positive
    # (coefficients c_i = a_(i+1) tau_lo^i, c_n = -rem tau_lo^n; degree n polynomial)
    cc = _ZEROS
    p = 1.0
    for i in range(n):
        cc = with_item(cc, i, a[i + 1] * p)
        p *= tau_lo
    cc = with_item(cc, n, -rem * p)
    binom_n = 1.0
    for i in range(n + 1):
        # b_i = sum_{j <= i} C(i, j) / C(n, j) c_j
        s = 0.0
        cij = 1.0
        cnj = 1.0
        for j in range(i + 1):
            s += cij / cnj * cc[j]
            cij = cij * (i - j) / (j + 1)
            cnj = cnj * (n - j) / (j + 1)
        if not s > 0.0:
            return False, 0.0, 0.0
    # the root of p and the velocity there; the velocity's remainder must be negligible
    tr = 0.5 * (tau_lo + tau_hi)
    v = 0.0
    for j in range(n, 0, -1):
        v = v * tr + j * a[j]
    if not v < 0.0 or (n + 1) * rem * tr ** n > 4.0 * EPS * -v:
        return False, 0.0, 0.0
    return True, tr, v


@jit
def phase_of(t, om):
    """t mod T, T = 2 pi / omega, in [0, T)."""
    period = 2.0 * math.pi / om
    ph = t - period * math.floor(t / period)
    if ph >= period:
        ph -= period
    return ph


__all__ = ["safe_step", "next_impact", "search_from", "short_hop", "phase_of", "step_caps", "step_cap", "OM"]
