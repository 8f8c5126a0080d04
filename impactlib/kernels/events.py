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
from .flight import (ALPHA, C_, CPH, FA, G, H0, HV0, K, M, NSEG, OM, PP, QQ, R, RES, SPH, T0, V0,
                     W0SQ, X0, derivative_bounds, flight_state, motion_bounds)

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
    e = np.empty(n + 1)
    e[0] = x0
    e[1] = u
    fj = 1.0
    for j in range(n - 1):
        # j-th derivative of cos(omega t): omega^j (cos, -sin, -cos, sin)[j mod 4]
        r4 = j % 4
        trig = cph if r4 == 0 else (-sph if r4 == 1 else (-cph if r4 == 2 else sph))
        e[j + 2] = (fj * trig - 2.0 * c * e[j + 1] - k * e[j]) / m
        fj *= om
    if not e[2] < 0.0:
        return False, 0.0, 0.0
    a = np.empty(n + 1)
    a[0] = 0.0
    fj = 1.0
    for j in range(1, n + 1):
        fj *= j
        a[j] = e[j] / fj
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
    cc = np.empty(n + 1)
    p = 1.0
    for i in range(n):
        cc[i] = a[i + 1] * p
        p *= tau_lo
    cc[n] = -rem * p
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


# ------------------------------------------------------------ the grid search

# layout of the per-run grid array: step, the homogeneous flow over one step
# (h, h') -> [[P11, P12], [P21, P22]] (h, h'), and the forcing's rotation by omega step
GSTEP, P11, P12, P21, P22, GCOS, GSIN, NGRID = range(8)
#: grid step of next_impact_grid, in units of 1 / (fastest rate of the run)
GRID_STEP = 0.5
#: no grid when a forcing period would take more steps than this (stiff flows): the
#: certified search's steps adapt to the decaying transient, a fixed grid cannot
GRID_MAX_STEPS_PER_PERIOD = 256.0


@jit
def search_grid(sp, rate):
    """The grid of :func:`next_impact_grid` for one run (an array of NGRID floats);
    grid[GSTEP] = 0 where no grid is used (resonance, k = 0, stiff flows)."""
    grid = np.zeros(NGRID)
    h = GRID_STEP / rate
    if sp[RES] != 0.0 or sp[W0SQ] <= 0.0 or 2.0 * math.pi / sp[OM] > GRID_MAX_STEPS_PER_PERIOD * h:
        return grid
    # the transition matrix: homogeneous solutions from (1, 0) and (0, 1), no forcing
    unit = np.zeros(NSEG)
    unit[H0] = 1.0
    unit[X0] = 1.0
    x, v, a, j, rh, xs = flight_state(sp, unit, h)
    grid[P11], grid[P21] = x, v
    unit[H0], unit[X0], unit[HV0], unit[V0] = 0.0, 0.0, 1.0, 1.0
    x, v, a, j, rh, xs = flight_state(sp, unit, h)
    grid[P12], grid[P22] = x, v
    grid[GCOS] = math.cos(sp[OM] * h)
    grid[GSIN] = math.sin(sp[OM] * h)
    grid[GSTEP] = h
    return grid


@jit
def _clear_of_root(v, a, m3):
    """T such that v tau + a tau^2 / 2 - m3 tau^3 / 6 > 0 on (0, T), for v > 0: the
    positive root of v + a tau / 2 - m3 tau^2 / 6 (cancellation-free form), less a
    relative 1e-12."""
    m3 = max(m3, 1e-300)
    d = math.sqrt(0.25 * a * a + 2.0 * m3 * v / 3.0)
    t = (0.5 * a + d) / (m3 / 3.0) if a >= 0.0 else 2.0 * v / (d - 0.5 * a)
    return t * (1.0 - 1e-12)


@jit
def _cubic_positive(f, v, a, m3, T):
    """True if f + v tau + a tau^2 / 2 - m3 tau^3 / 6 > 0 on [0, T]: all its Bernstein
    coefficients on [0, T] are (a sufficient test, no root finding)."""
    vt = v * T
    at = a * T * T
    return (f > 0.0 and f + vt / 3.0 > 0.0 and f + 2.0 * vt / 3.0 + at / 6.0 > 0.0
            and f + vt + 0.5 * at - m3 * T * T * T / 6.0 > 0.0)


@jit
def _hermite_root(fa, va, fb, vb, h):
    """Approximate root in (0, h) of the cubic Hermite interpolant of (fa, va) at 0 and
    (fb, vb) at h, fa > 0 >= fb: a starting guess only (Newton on the closed form
    follows), from the secant root and three Newton steps on the cubic."""
    c1 = va * h
    c2 = -3.0 * fa - 2.0 * va * h + 3.0 * fb - vb * h
    c3 = 2.0 * fa + va * h - 2.0 * fb + vb * h
    th = fa / (fa - fb)
    for _ in range(3):
        d = c1 + th * (2.0 * c2 + 3.0 * th * c3)
        if d >= 0.0:
            break
        th_new = th - (fa + th * (c1 + th * (c2 + th * c3))) / d
        if not (0.0 < th_new < 1.0):
            break
        th = th_new
    return th * h


@jit
def _newton_root(sp, seg, s, lo, hi):
    """Newton on f = x - g from s, staying in (lo, hi].  Returns (ok, root, v, a,
    evaluations); ok only if every iterate went down the wall (v < 0) and the last step
    is at rounding level."""
    g = sp[G]
    t0 = abs(seg[T0])
    n = 0
    for _ in range(8):
        x, v, a, j, rh, xs = flight_state(sp, seg, s)
        n += 1
        if not v < 0.0:
            break
        ds = -(x - g) / v
        s_new = s + ds
        if not (lo < s_new <= hi):
            break
        if abs(ds) <= 4.0 * EPS * (t0 + s):
            # the state at the root, to first order in the last (rounding-level) step
            return True, s_new, v + a * ds, a, n
        s = s_new
    return False, s, 0.0, 0.0, n


@jit
def next_impact_grid(sp, seg, s_end, hmax, max_steps, grid, s_guess):
    """:func:`next_impact` with fewer closed-form evaluations and the same guarantee.

    A hop from the wall short enough for its Taylor polynomial to fix the root to
    rounding (chatter) is taken by :func:`short_hop`, without closed-form evaluation.

    The flight is advanced on a fixed grid by its exact linear recurrence (``grid``,
    from :func:`search_grid`): no transcendental function per node.  Each grid interval
    is certified free of the wall from the values and slopes at its ends: f = x - g
    differs from its cubic Hermite interpolant by at most M4 h^4 / 384 (M4 bounds the
    fourth derivative, flight.derivative_bounds), and the interpolant lies above the
    least of its Bernstein coefficients f0, f0 + v0 h / 3, f1 - v1 h / 3, f1.  The first
    interval, which starts on the wall, is certified by the cubic lower bounds of the
    module docstring from both of its ends (checked by their Bernstein coefficients).  At the first interval not certified, the
    root is sought by Newton on the closed form from ``s_guess`` (the caller's
    prediction, e.g. the hop of a periodic orbit) or from the interpolant's root, and
    accepted only if the cubic lower bounds from the interval's start and, backwards,
    from the root cover the gap between them (so no earlier root).  Otherwise (grazing
    dips, the segment's end, no grid) the search is :func:`next_impact`'s certified walk.  Rounding of the recurrence is bounded generously (32 eps of the
    terms' size per step) and subtracted.  Returns as next_impact.
    """
    h = grid[GSTEP]
    g = sp[G]
    x0 = seg[X0]
    v0 = seg[V0]
    if x0 == g and v0 > 0.0:
        ok, s, v = short_hop(sp, seg, s_end)
        if ok:
            return IMPACT, s, v, 0
    if h <= 0.0 or (x0 - g <= 0.0 and v0 <= 0.0):
        return next_impact(sp, seg, s_end, hmax, max_steps)
    om, pp, qq = sp[OM], sp[PP], sp[QQ]
    m, c, k = sp[M], sp[C_], sp[K]
    w0sq = sp[W0SQ]
    hh, hd = seg[H0], seg[HV0]
    cph, sph = seg[CPH], seg[SPH]
    rh0 = math.sqrt(hd * hd + w0sq * hh * hh)
    m3, m4 = derivative_bounds(sp, rh0, s_end, x0, v0, s_end)
    herm = m4 * (h * h) * (h * h) / 384.0
    # size of the terms summed at a node (|h| <= rh0 / w0, |x_p| <= FA), for rounding
    size = rh0 / math.sqrt(w0sq) + rh0 + sp[FA] * (1.0 + om) + abs(g) + abs(x0)
    fs, vs = x0 - g, v0
    as_ = (cph - 2.0 * c * v0 - k * x0) / m
    s = 0.0
    n = 0
    f1 = fs
    v1 = vs
    hh1, hd1, cph1, sph1 = hh, hd, cph, sph
    while True:
        s1 = s + h
        if s1 >= s_end:
            break
        hh1 = grid[P11] * hh + grid[P12] * hd
        hd1 = grid[P21] * hh + grid[P22] * hd
        cph1 = cph * grid[GCOS] - sph * grid[GSIN]
        sph1 = sph * grid[GCOS] + cph * grid[GSIN]
        f1 = hh1 + pp * cph1 + qq * sph1 - g
        v1 = hd1 + om * (qq * cph1 - pp * sph1)
        n += 1
        rnd = 32.0 * EPS * (n + 1) * size
        if n == 1:
            # starts on the wall: forward cubic bound from 0, backward from h
            a1 = (cph1 - 2.0 * c * v1 - k * (f1 + g)) / m
            tf = _clear_of_root(vs, as_, m3) if vs > 0.0 else 0.0
            ok = f1 - rnd > 0.0 and (tf >= h or _cubic_positive(f1 - rnd, -v1, a1, m3, h - tf))
        else:
            ok = min(min(fs, fs + vs * h / 3.0), min(f1 - v1 * h / 3.0, f1)) > herm + rnd
        if not ok:
            break
        s = s1
        hh, hd, cph, sph, fs, vs = hh1, hd1, cph1, sph1, f1, v1
    # [s, s + h] is not certified (or passes s_end): the wall is near
    evals = 0
    if s > 0.0 and s + h < s_end:
        lo = s
        hi = s + h
        guess = -1.0
        if f1 <= 0.0:
            if not lo < s_guess <= hi:
                guess = s + _hermite_root(fs, vs, f1, v1, h)
        elif s + 2.0 * h < s_end:
            # the crossing may lie just past the node: look one interval further
            hh2 = grid[P11] * hh1 + grid[P12] * hd1
            hd2 = grid[P21] * hh1 + grid[P22] * hd1
            cph2 = cph1 * grid[GCOS] - sph1 * grid[GSIN]
            sph2 = sph1 * grid[GCOS] + cph1 * grid[GSIN]
            f2 = hh2 + pp * cph2 + qq * sph2 - g
            v2 = hd2 + om * (qq * cph2 - pp * sph2)
            hi = s + 2.0 * h
            if f2 <= 0.0 and not lo < s_guess <= hi:
                guess = s + h + _hermite_root(f1, v1, f2, v2, h)
        if lo < s_guess <= hi:
            guess = s_guess
        if guess > 0.0:
            ok, r, vr, ar, ne = _newton_root(sp, seg, guess, lo, hi)
            evals += ne
            if ok:
                as_ = (cph - 2.0 * c * vs - k * (fs + g)) / m
                gap = r - s
                rnd = 32.0 * EPS * (n + 1) * size
                tb = _clear_of_root(-vr, ar, m3)
                if tb >= gap or _cubic_positive(fs - rnd, vs, as_, m3, gap - tb):
                    return IMPACT, r, vr, evals
    # the certified walk, from the start: where it is needed (grazing dips, the run's
    # end, chatter) its steps are few, and its results are those of next_impact exactly
    kind, sr, vr, ns = next_impact(sp, seg, s_end, hmax, max_steps - evals)
    return kind, sr, vr, ns + evals


@jit
def phase_of(t, om):
    """t mod T, T = 2 pi / omega, in [0, T)."""
    period = 2.0 * math.pi / om
    ph = t - period * math.floor(t / period)
    if ph >= period:
        ph -= period
    return ph


__all__ = ["safe_step", "next_impact", "next_impact_grid", "search_from", "search_grid", "short_hop", "phase_of", "step_caps", "step_cap", "OM"]
