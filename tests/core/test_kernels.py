"""The kernels themselves: flight_state against the mpmath closed form in every damping
regime, the impact searches against exact first roots of adversarial dips, and the
kernels called from other njit code."""
import math

import mpmath
import numpy as np
import pytest
from numba import njit

import impactlib as il
from impactlib.kernels import events as E
from impactlib.kernels import flight as F
from impactlib.kernels import grid as GR
from impactlib.verify.reference import mp_state

from core_helpers import EPS, PAPER

REGIMES = {
    "underdamped": PAPER,
    "undamped": PAPER.replace(c=0.0),
    "critical": PAPER.replace(c=1.0),
    "crit+1e-9": PAPER.replace(c=1.0 + 1e-9),
    "crit-1e-9": PAPER.replace(c=1.0 - 1e-9),
    "overdamped": PAPER.replace(c=2.0),           # sqrt(-q) s from 0 to ~17
    "overdamped, far": PAPER.replace(c=5.0),      # sqrt(-q) s beyond 20: two exponentials
    "no spring": PAPER.replace(k=0.0),
    "resonance": PAPER.replace(c=0.0, omega=1.0),
    "stiff": PAPER.replace(k=1e4, omega=1.0),
}


def constants(p):
    return F.system_constants(p.m, p.c, p.k, p.g, p.r, p.omega)


@pytest.mark.parametrize("name", REGIMES)
def test_flight_state_matches_mpmath_in_every_regime(name):
    """x, v at random times of random flights, against the closed form in mpmath (40
    digits).  Tolerance: a few ulps of the terms summed (flight_state's own size
    estimate xs), plus the rounding of the arguments omega t and the decay rate times s
    (relative eps each), which moves the result by up to eps (omega t + rate s) times
    the state's scale."""
    p = REGIMES[name]
    sp = constants(p)
    rate = p.rate()
    rng = np.random.default_rng(list(REGIMES).index(name))
    for _ in range(12):
        t0 = float(rng.uniform(0.0, 50.0))
        x0 = float(rng.uniform(-1.0, 1.0))
        v0 = float(rng.uniform(-2.0, 2.0))
        seg = F.start_segment(sp, t0, x0, v0)
        ss = np.sort(rng.uniform(0.0, 10.0, 6))
        ss[0] = float(rng.uniform(0.0, 1e-6))       # tiny s: the increment form
        xr, vr = mp_state(p, t0 + ss, x0=x0, v0=v0, t0=t0)
        for s, xe, ve in zip(ss, xr, vr):
            x, v, a, j, rh, xs = F.flight_state(sp, seg, s)
            scale = abs(xe) + abs(ve) / rate + abs(x0) + abs(v0) / rate + sp[F.FA]
            arg = 1.0 + p.omega * (t0 + s) + rate * s
            assert abs(x - xe) <= 32 * EPS * (xs + arg * scale), (s, x, xe)
            assert abs(v - ve) <= 32 * EPS * rate * (xs + arg * scale), (s, v, ve)
            # and the acceleration is Eq. (1) itself
            acc = (math.cos(p.omega * (t0 + s)) - 2 * p.c * v - p.k * x) / p.m
            assert abs(a - acc) <= 64 * EPS * rate * rate * (xs + arg * scale)


def _derivatives(p, t, x, v, n):
    """x, x', ..., x^(n) at time t from the state (x, v) by Eq. (1) differentiated:
    m x^(j+2) = (d/dt)^j cos(omega t) - 2 c x^(j+1) - k x^(j)."""
    d = [x, v]
    w = p.omega
    for j in range(n - 1):
        trig = (math.cos, lambda z: -math.sin(z), lambda z: -math.cos(z), math.sin)[j % 4]
        d.append((w ** j * trig(w * t) - 2 * p.c * d[j + 1] - p.k * d[j]) / p.m)
    return d


@pytest.mark.parametrize("name", [*REGIMES, "resonance, c=1e-10"])
def test_energy_bounds_hold_along_flights(name):
    """flight.motion_bounds against the derivatives along the closed form (x, v from
    flight_state, tested above; higher derivatives from Eq. (1) at each sample), for
    orders 3, 4 and 9 (the impact search's and the short hop's) over spans of 0.01 to 5
    time units from random states.  Where the particular solution is large
    (c = 1e-10 at omega = omega_n), derivative_bounds is the energy bound, not ~1/c."""
    p = REGIMES.get(name) or PAPER.replace(c=1e-10, omega=1.0)
    sp = constants(p)
    rng = np.random.default_rng(7 + list(REGIMES).index(name) if name in REGIMES else 99)
    for _ in range(8):
        t0 = float(rng.uniform(0.0, 50.0))
        x0 = float(rng.uniform(-1.0, 1.0))
        v0 = float(rng.uniform(-2.0, 2.0))
        span = float(10.0 ** rng.uniform(-2.0, math.log10(5.0)))
        seg = F.start_segment(sp, t0, x0, v0)
        peak = np.zeros(10)
        for s in np.linspace(0.0, span, 400):
            x, v = F.flight_state(sp, seg, s)[:2]
            peak = np.maximum(peak, np.abs(_derivatives(p, t0 + s, x, v, 9)))
        for order in (3, 4, 9):
            lower, upper = F.motion_bounds(sp, x0, v0, span, order)
            # rounding of the sampled values: a relative 1e-9 is far above it
            assert peak[order - 1] <= lower * (1 + 1e-9) and peak[order] <= upper * (1 + 1e-9)
        if name == "resonance, c=1e-10":
            rh = F.flight_state(sp, seg, 0.0)[4]
            m3, m4 = F.derivative_bounds(sp, rh, span, x0, v0, span)
            assert m3 == F.motion_bounds(sp, x0, v0, span, 4)[0] < 1e3


def _steady(p, t):
    """The steady forced orbit x_p = P cos(wt) + Q sin(wt) = A cos(wt - phi)."""
    det = p.k - p.m * p.omega ** 2
    d = det * det + (2 * p.c * p.omega) ** 2
    P, Q = det / d, 2 * p.c * p.omega / d
    w = p.omega
    return (P * math.cos(w * t) + Q * math.sin(w * t),
            w * (Q * math.cos(w * t) - P * math.sin(w * t)), math.sqrt(P * P + Q * Q),
            math.atan2(Q, P))


def _first_dip_root(p, t0, A, phi, delta):
    """First t > t0 with A cos(wt - phi) = -A (1 - delta), in mpmath: the entry root
    w t - phi = pi - arccos(1 - delta) + 2 pi n."""
    mp = mpmath.mp.clone() if hasattr(mpmath.mp, "clone") else mpmath.mp
    mp.dps = 40
    w = mpmath.mpf(p.omega)
    base = mpmath.pi - mpmath.acos(1 - mpmath.mpf(delta)) + mpmath.mpf(phi)
    n = mpmath.ceil((w * t0 - base) / (2 * mpmath.pi))
    return float((base + 2 * mpmath.pi * n) / w)


@pytest.mark.parametrize("delta", [1e-1, 1e-3, 1e-6, 1e-9, 1e-12])
@pytest.mark.parametrize("omega", [0.5, 2.0, 4.0])
def test_searches_find_the_first_root_of_a_shallow_dip(delta, omega):
    """Start on the steady forced orbit (no transient) with the wall just above its
    minimum: a dip delta A deep, as short as 2 sqrt(2 delta) / omega.  Both the certified
    walk (next_impact) and the grid search (next_impact_grid, with no guess, with a guess
    at a later dip and with a random guess) must return the entry root of the FIRST dip,
    known in closed form (arccos), to the time its depth fixes in float64:
    eps A / |v| at the root, |v| = A omega sqrt(2 delta - delta^2)."""
    base = PAPER.replace(omega=omega)
    rng = np.random.default_rng(int(omega * 1e3) + int(-math.log10(delta)))
    for _ in range(6):
        t0 = float(rng.uniform(0.0, 30.0))
        x0, v0, A, phi = _steady(base, t0)
        while x0 <= -A * (1.0 - 2 * delta):     # start above the wall, outside the dip
            t0 += 0.1
            x0, v0, A, phi = _steady(base, t0)
        p = base.replace(g=-A * (1.0 - delta))
        sp = constants(p)
        sp_rate = p.rate()
        hmax = float(E.step_caps(sp))
        grid = GR.search_grid(sp, sp_rate)
        assert grid[GR.GSTEP] > 0.0
        seg = F.start_segment(sp, t0, x0, v0)
        t_ref = _first_dip_root(p, t0, A, phi, delta)
        v_root = A * omega * math.sqrt(2 * delta - delta * delta)
        tol = 64 * EPS * (A / v_root + t_ref)
        s_end = 3 * p.T + (t_ref - t0)
        results = [E.next_impact(sp, seg, s_end, hmax, 10**6)]
        for guess in (-1.0, t_ref - t0 + p.T, float(rng.uniform(0.0, 2 * (t_ref - t0)))):
            results.append(GR.next_impact_grid(sp, seg, s_end, hmax, 10**6, grid, guess))
        for kind, s, v, n in results:
            assert kind == E.IMPACT
            assert abs(t0 + s - t_ref) <= tol, (delta, t0, s, t_ref - t0)
            assert v <= 0.0


@pytest.mark.parametrize("delta", [1e-3, 1e-6, 1e-9, 1e-12])
def test_searches_do_not_invent_an_impact_at_a_near_miss(delta):
    """The same orbit with the wall delta A BELOW its minimum: no impact in 5 periods,
    however shallow the clearance, with any guess."""
    rng = np.random.default_rng(7)
    for _ in range(6):
        t0 = float(rng.uniform(0.0, 30.0))
        x0, v0, A, phi = _steady(PAPER, t0)
        p = PAPER.replace(g=-A * (1.0 + delta))
        sp = constants(p)
        hmax = float(E.step_caps(sp))
        grid = GR.search_grid(sp, p.rate())
        seg = F.start_segment(sp, t0, x0, v0)
        s_end = 5 * p.T
        t_min = _first_dip_root(p, t0, A, phi, 0.0)      # where the orbit is lowest
        for kind, s, v, n in [E.next_impact(sp, seg, s_end, hmax, 10**6)] + [
                GR.next_impact_grid(sp, seg, s_end, hmax, 10**6, grid, guess)
                for guess in (-1.0, t_min - t0)]:
            assert kind == E.NO_IMPACT and s == s_end


def test_short_hops_match_the_certified_walk_and_mpmath():
    """Chatter hops at omega = 0.2 taken by the Taylor short hop agree with the certified
    walk and with the mpmath reference's first impact from the same start."""
    from impactlib.verify.reference import mp_impacts

    p = PAPER.replace(omega=0.2)
    sp = constants(p)
    hmax = float(E.step_caps(sp))
    sol = il.simulate(p, t_end=20.0, t_record=0.0)
    taken = 0
    for t, v in list(zip(sol.impacts.t, sol.impacts.v))[-25:]:
        u = -p.r * v
        seg = F.start_segment(sp, t, p.g, u)
        ok, s, vs = E.short_hop(sp, seg, 100.0)
        if not ok:
            continue
        taken += 1
        ref = mp_impacts(p, 1, x0=p.g, v0=float(u), t0=float(t))
        assert abs(t + s - ref.t[0]) <= 4 * EPS * t
        assert abs(vs - ref.v[0]) <= 64 * EPS * abs(ref.v[0])
        kind, s2, v2, n = E.next_impact(sp, seg, 100.0, hmax, 10**6)
        assert abs(s - s2) <= 8 * EPS * t
    assert taken >= 10


def test_hops_landing_in_the_first_grid_interval_match_the_walk_and_mpmath():
    """Chatter hops too long for the Taylor short hop that land inside the grid's first
    interval (Newton on the closed form, certified by cubic bounds forward from the wall
    and backward from the root) agree with the certified walk (next_impact) to a few
    ulps of t, and a sample with the mpmath reference's first impact."""
    from impactlib.verify.reference import mp_impacts

    p = PAPER.replace(omega=0.2)
    sp = constants(p)
    hmax = float(E.step_caps(sp))
    grid = GR.search_grid(sp, p.rate())
    h = grid[GR.GSTEP]
    sol = il.simulate(p, t_end=300.0, t_record=0.0)
    taken = fewer = 0
    for t, v in zip(sol.impacts.t, sol.impacts.v):
        u = -p.r * v
        seg = F.start_segment(sp, t, p.g, u)
        if u <= 0.0 or E.short_hop(sp, seg, 100.0)[0]:
            continue
        k1, s1, v1, n1 = E.next_impact(sp, seg, 100.0, hmax, 10**6)
        if not (k1 == E.IMPACT and s1 < h):
            continue
        k2, s2, v2, n2 = GR.next_impact_grid(sp, seg, 100.0, hmax, 10**6, grid, -1.0)
        assert k2 == E.IMPACT
        assert abs(s2 - s1) <= 8 * EPS * (t + s1), (t, s1, s2)
        # v moves by the acceleration times the time's rounding
        a = F.flight_state(sp, seg, s1)[2]
        assert abs(v2 - v1) <= 8 * EPS * (t + s1) * abs(a) + 64 * EPS * abs(v1), (t, v1, v2)
        fewer += n2 < n1
        if taken % 8 == 0:
            ref = mp_impacts(p, 1, x0=p.g, v0=float(u), t0=float(t))
            assert abs(t + s2 - ref.t[0]) <= 8 * EPS * (t + s2)
        taken += 1
    # the grid search took them itself, not by falling back to the walk
    assert taken >= 20 and fewer >= 0.9 * taken, (taken, fewer)


@njit
def _caller(sp, seg, s_end, hmax, grid, ts):
    # a user's own njit code calling the kernels
    out = np.empty(ts.shape[0])
    for i in range(ts.shape[0]):
        out[i] = F.flight_state(sp, seg, ts[i])[0]
    k1, s1, v1, n1 = E.next_impact(sp, seg, s_end, hmax, 10**6)
    k2, s2, v2, n2 = GR.next_impact_grid(sp, seg, s_end, hmax, 10**6, grid, -1.0)
    return out, s1, s2


def test_kernels_are_callable_from_njit_code():
    sp = constants(PAPER)
    seg = F.start_segment(sp, 3.0, 0.0, 1.5)
    grid = GR.search_grid(sp, PAPER.rate())
    ts = np.linspace(0.0, 2.0, 5)
    xs, s1, s2 = _caller(sp, seg, 50.0, float(E.step_caps(sp)), grid, ts)
    np.testing.assert_array_equal(xs, [F.flight_state(sp, seg, t)[0] for t in ts])
    assert s1 == E.next_impact(sp, seg, 50.0, float(E.step_caps(sp)), 10**6)[1]
    assert abs(s1 - s2) <= 8 * EPS * (3.0 + s1)
