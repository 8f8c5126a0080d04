"""The grid search: the next impact with few closed-form evaluations and the guarantee of
:func:`impactlib.kernels.events.next_impact` (no earlier root is ever skipped).

The flight is advanced on a fixed grid by its exact linear recurrence and each grid
interval is certified free of the wall from the values and slopes at its ends; at the
first interval not certified the root is found by Newton on the closed form and accepted
only with a certificate that the gap before it is clear.  Where that fails (grazing
dips, the segment's end, stiff flows, resonance) the search is the certified walk of
events.py; chatter hops short enough for a Taylor polynomial are events.short_hop's.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit
from .events import EPS, IMPACT, next_impact, short_hop
from .flight import C_, CPH, FA, G, H0, HRATE, HV0, K, M, NSEG, OM, PP, QQ, RES, SPH, T0, V0, W0SQ, X0
from .flight import derivative_bounds, flight_state

# layout of the per-run grid array: step, the homogeneous flow over one step
# (h, h') -> [[P11, P12], [P21, P22]] (h, h'), the forcing's rotation by omega step, and
# the same two over a double step (the stride far from the wall), in the same order
GSTEP, P11, P12, P21, P22, GCOS, GSIN, D11, D12, D21, D22, DCOS, DSIN, NGRID = range(14)
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
    x, v, a, j, rh, xs = flight_state(sp, unit, 2.0 * h)
    grid[D12], grid[D22] = x, v
    unit[H0], unit[X0], unit[HV0], unit[V0] = 1.0, 1.0, 0.0, 0.0
    x, v, a, j, rh, xs = flight_state(sp, unit, 2.0 * h)
    grid[D11], grid[D21] = x, v
    grid[GCOS] = math.cos(sp[OM] * h)
    grid[GSIN] = math.sin(sp[OM] * h)
    grid[DCOS] = math.cos(sp[OM] * 2.0 * h)
    grid[DSIN] = math.sin(sp[OM] * 2.0 * h)
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
def _clears(v, a, m3, T):
    """True if v tau + a tau^2 / 2 - m3 tau^3 / 6 > 0 on (0, T], for v > 0, without a
    square root: divided by tau it is a concave quadratic (m3 >= 0), positive on [0, T]
    where it is at T; its value there must exceed 1e-12 of its terms (rounding), as
    :func:`_clear_of_root` keeps 1e-12 from its root."""
    at = 0.5 * a * T
    mt = m3 * T * T / 6.0
    return v + at - mt > 1e-12 * (v + abs(at) + mt)


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
def _hop_root(v0, a0, j0, h):
    """Approximate landing time of a hop from the wall with slope v0 > 0, acceleration
    a0 < 0 and jerk j0 at the start: the root of its Taylor cubic divided by tau,
    v0 + a0 tau / 2 + j0 tau^2 / 6 (the parabola's where that has none), at most h; a
    starting guess only (Newton on the closed form follows)."""
    b = 0.5 * a0
    d = b * b - 4.0 * (j0 / 6.0) * v0
    tau = 2.0 * v0 / (math.sqrt(d) - b) if d >= 0.0 else -2.0 * v0 / a0
    return min(tau, h)


@jit
def _newton_root(sp, seg, s, lo, hi):
    """Newton on f = x - g from s, staying in (lo, hi].  Returns (ok, root, v, a,
    evaluations); ok only if every iterate went down the wall (v < 0) and the last step
    is at rounding level, or the step after it would be (see below)."""
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
        tol = 4.0 * EPS * (t0 + s)
        if abs(ds) <= tol:
            # the state at the root, to first order in the last (rounding-level) step
            return True, s_new, v + a * ds, a, n
        if abs(a) * ds * ds <= 2e-3 * tol * -v and v + ds * (a + 0.5 * j * ds) < 0.0:
            # Newton's next step, about a ds^2 / (2 v), would be a thousandth of the
            # rounding level: s_new is the root to rounding without another evaluation
            # (the state there from the Taylor polynomial at s)
            return True, s_new, v + ds * (a + 0.5 * j * ds), a + j * ds, n
        s = s_new
    return False, s, 0.0, 0.0, n


@jit
def _grid_step(grid, o, hh, hd, cph, sph, pp, qq, om, g):
    """One step along the grid (o = P11) or a double step (o = D11) from the node
    (hh, hd, cph, sph): the next node's homogeneous part and forcing phase, and there
    f = x - g and its slope."""
    hh1 = grid[o] * hh + grid[o + 1] * hd
    hd1 = grid[o + 2] * hh + grid[o + 3] * hd
    cph1 = cph * grid[o + 4] - sph * grid[o + 5]
    sph1 = sph * grid[o + 4] + cph * grid[o + 5]
    return hh1, hd1, cph1, sph1, hh1 + pp * cph1 + qq * sph1 - g, hd1 + om * (qq * cph1 - pp * sph1)


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
    least of its Bernstein coefficients f0, f0 + v0 h / 3, f1 - v1 h / 3, f1.  Far from
    the wall the grid strides two steps at a time, each double interval certified the
    same way (its bound 16 times the single step's), until the first that is not.  The
    first interval, which starts on the wall, is certified by the cubic lower bounds of
    events.py from both of its ends (checked by their Bernstein coefficients).  A hop
    from the wall landing inside that first interval (chatter) is found by Newton from
    the root of its Taylor cubic and certified by the cubic bounds forward from the wall
    and backward from the root.  At the first interval not certified, the
    root is sought by Newton on the closed form from ``s_guess`` (the caller's
    prediction, e.g. the hop of a periodic orbit) or from the interpolant's root, and
    accepted only if the cubic lower bounds from the interval's start and, backwards,
    from the root cover the gap between them (so no earlier root).  Otherwise (grazing
    dips, the segment's end, no grid) the search is :func:`next_impact`'s certified walk.
    Rounding of the recurrence is bounded generously (32 eps of the terms' size per
    step) and subtracted.  Returns as next_impact.
    """
    h = grid[GSTEP]
    g = sp[G]
    x0 = seg[X0]
    v0 = seg[V0]
    om, pp, qq = sp[OM], sp[PP], sp[QQ]
    m, c, k = sp[M], sp[C_], sp[K]
    w0sq = sp[W0SQ]
    hh, hd = seg[H0], seg[HV0]
    cph, sph = seg[CPH], seg[SPH]
    as_ = (cph - 2.0 * c * v0 - k * x0) / m
    # short_hop's own first test (its parabola's length against the fastest rate),
    # here so that a hop too long for it does not pay its call
    if x0 == g and v0 > 0.0 and as_ < 0.0 and 2.0 * v0 / -as_ * max(om, sp[HRATE]) <= 0.5:
        ok, s, v = short_hop(sp, seg, s_end)
        if ok:
            return IMPACT, s, v, 0
    if h <= 0.0 or (x0 - g <= 0.0 and v0 <= 0.0):
        return next_impact(sp, seg, s_end, hmax, max_steps)
    rh0 = math.sqrt(hd * hd + w0sq * hh * hh)
    m3, m4 = derivative_bounds(sp, rh0, s_end, x0, v0, s_end)
    herm = m4 * (h * h) * (h * h) / 384.0
    # size of the terms summed at a node (|h| <= rh0 / w0, |x_p| <= FA), for rounding
    size = rh0 / math.sqrt(w0sq) + rh0 + sp[FA] * (1.0 + om) + abs(g) + abs(x0)
    rnd_step = 32.0 * EPS * size
    h3 = h / 3.0
    fs, vs = x0 - g, v0
    s = 0.0
    n = 0
    nodes = 1.0                     # n + 1, as a float
    f1 = fs
    v1 = vs
    hh1, hd1, cph1, sph1 = hh, hd, cph, sph
    # far from the wall the grid strides two steps at a time, certified by the same
    # bound for a double step (16 herm); from the first double step not certified on,
    # single steps
    stride = True
    herm2 = 16.0 * herm
    h23 = 2.0 * h3
    while True:
        if stride and n > 0:
            s2 = s + 2.0 * h
            if s2 < s_end:
                hh2, hd2, cph2, sph2, f2, v2 = _grid_step(grid, D11, hh, hd, cph, sph,
                                                          pp, qq, om, g)
                if min(min(fs, fs + vs * h23), min(f2 - v2 * h23, f2)) > herm2 + rnd_step * (nodes + 1.0):
                    n += 1
                    nodes += 1.0
                    s = s2
                    hh, hd, cph, sph, fs, vs = hh2, hd2, cph2, sph2, f2, v2
                    continue
            stride = False
        s1 = s + h
        if s1 >= s_end:
            break
        hh1, hd1, cph1, sph1, f1, v1 = _grid_step(grid, P11, hh, hd, cph, sph, pp, qq, om, g)
        n += 1
        nodes += 1.0
        rnd = rnd_step * nodes
        if n == 1:
            # starts on the wall: forward cubic bound from 0 (over the whole interval, or
            # up to its root), backward from h
            ok = f1 - rnd > 0.0
            if ok and not (vs > 0.0 and _clears(vs, as_, m3, h)):
                a1 = (cph1 - 2.0 * c * v1 - k * (f1 + g)) / m
                tf = _clear_of_root(vs, as_, m3) if vs > 0.0 else 0.0
                ok = tf >= h or _cubic_positive(f1 - rnd, -v1, a1, m3, h - tf)
        else:
            ok = min(min(fs, fs + vs * h3), min(f1 - v1 * h3, f1)) > herm + rnd
        if not ok:
            break
        s = s1
        hh, hd, cph, sph, fs, vs = hh1, hd1, cph1, sph1, f1, v1
    # [s, s + h] is not certified (or passes s_end): the wall is near
    evals = 0
    if s == 0.0 and fs == 0.0 and vs > 0.0 and as_ < 0.0 and f1 <= 0.0 and h < s_end:
        # a hop from the wall landing in the first interval (chatter): Newton from the
        # caller's guess or the start's Taylor cubic, accepted if the cubic lower bounds
        # forward from the wall and backward from the root cover the hop
        j0 = (-om * sph - 2.0 * c * as_ - k * vs) / m
        guess = s_guess if 0.0 < s_guess <= h else _hop_root(vs, as_, j0, h)
        ok, r, vr, ar, ne = _newton_root(sp, seg, guess, 0.0, h)
        evals += ne
        if ok and (_clears(-vr, ar, m3, r) or _clears(vs, as_, m3, r)
                   or _clear_of_root(vs, as_, m3) + _clear_of_root(-vr, ar, m3) >= r):
            return IMPACT, r, vr, evals
    elif s > 0.0 and s + h < s_end:
        lo = s
        hi = s + h
        guess = -1.0
        if f1 <= 0.0:
            if not lo < s_guess <= hi:
                guess = s + _hermite_root(fs, vs, f1, v1, h)
        elif s + 2.0 * h < s_end:
            # the crossing may lie just past the node: look one interval further
            hh2, hd2, cph2, sph2, f2, v2 = _grid_step(grid, P11, hh1, hd1, cph1, sph1,
                                                      pp, qq, om, g)
            hi = s + 2.0 * h
            if f2 <= 0.0 and not lo < s_guess <= hi:
                guess = s + h + _hermite_root(f1, v1, f2, v2, h)
        if lo < s_guess <= hi:
            guess = s_guess
        if guess > 0.0:
            ok, r, vr, ar, ne = _newton_root(sp, seg, guess, lo, hi)
            evals += ne
            if ok:
                # the backward bound from the root over the whole gap, or up to its root
                # and the forward bound from s over the rest
                gap = r - s
                if _clears(-vr, ar, m3, gap):
                    return IMPACT, r, vr, evals
                as_ = (cph - 2.0 * c * vs - k * (fs + g)) / m
                rnd = rnd_step * nodes
                tb = _clear_of_root(-vr, ar, m3)
                if tb >= gap or _cubic_positive(fs - rnd, vs, as_, m3, gap - tb):
                    return IMPACT, r, vr, evals
    # the certified walk, from the start: where it is needed (grazing dips, the run's
    # end, chatter) its steps are few, and its results are those of next_impact exactly
    kind, sr, vr, ns = next_impact(sp, seg, s_end, hmax, max_steps - evals)
    return kind, sr, vr, ns + evals


__all__ = ["search_grid", "next_impact_grid", "GSTEP", "NGRID", "GRID_STEP"]
