"""The early summation of a chatter (chatter.tail_bound, tail_length, impact_outcome)
against the mpmath reference, which steps through every hop until the rebound is below
v_stop = 1e-16.

Tolerances
----------
* The reference stops a chatter at its first rebound below v_stop; the hops it leaves out
  last at most about 2 v_stop / ((1 - r) A), A the push into the wall there: allowed twice.
* Summed from the reference's own impact (t, v0) (rounded to float64), the accumulation
  time is off by at most the kernel's bound ``err`` plus rounding: t and v0 rounded to
  half an ulp and Newton's stopping rule 4 eps (t + tau), allowed as 8 eps (t + tau).
* Summed inside a run, the tail starts from the run's own last impact, which carries the
  rounding of the hops resolved before it: the accumulation time is compared with the
  rounding model of test_exact_accuracy (8 eps X / ((1 - r) |v_last|)) and with 64 eps t
  (16 impact-time roundings of 4 eps t), and the early path is asserted to have been
  taken at hops at least 10 times longer than engine.TAIL_TOL.
"""
import math

import numpy as np
import pytest

import impactlib as il
from impactlib.kernels.engine import TAIL_TOL
from impactlib.kernels.chatter import (FLY, STICK, impact_outcome, tail_bound, tail_floor_terms,
                                      tail_length)
from impactlib.kernels.flight import system_constants
from impactlib.verify.report import CASE_BY_NAME, reference, steady_orbit

from core_helpers import EPS, PAPER, mp_cached

V_STOP = 1e-16          # mp_impacts' default


def constants(p):
    return system_constants(p.m, p.c, p.k, p.g, p.r, p.omega)


def push(p, t):
    """A = (k g - cos(omega t)) / m, the net push into the wall at rest."""
    return (p.k * p.g - math.cos(p.omega * t)) / p.m


def ref_error(p, t_end):
    return 2.0 * 2.0 * V_STOP / ((1.0 - p.r) * push(p, t_end))


CHATTERS = {
    "omega=0.2": (PAPER.replace(omega=0.2), 25.0),
    "c=5": (CASE_BY_NAME["c=5"].params, CASE_BY_NAME["c=5"].t_end),
    "r=0.5": (PAPER.replace(omega=0.2, r=0.5), 25.0),
    "preload 0.3": (PAPER.replace(omega=0.3, g=0.3), 30.0),
}


def chatter_reference(name):
    p, t_max = CHATTERS[name]
    if name == "c=5":
        return reference(CASE_BY_NAME["c=5"])
    return mp_cached(p, 100_000, t_max=t_max)


@pytest.mark.parametrize("name", list(CHATTERS))
def test_summed_tail_from_reference_impacts_is_within_its_bound(name):
    """From every reference impact of a chatter where the bound holds, long before the
    last hops (hops of 1e-4 time scales and more), the summed tail ends where the
    reference's stepped-through chatter ends, within the bound.  Without the bound's
    correction term (Budd & Dux's 2 v0 / (1 - r) alone) the error exceeds that tolerance
    by orders of magnitude, so the test sees the correction."""
    p, _ = CHATTERS[name]
    R = chatter_reference(name)
    assert R.chatter_ends, "the reference case has a chatter"
    t_ref = R.chatter_ends[0]
    sp = constants(p)
    rate = p.rate()
    checked = long_hops = 0
    for tm, vm in zip(R.t_mp, R.v_mp):
        t = float(tm)
        if t >= t_ref:
            break
        v0 = float(-p.r * vm)
        ok, target, err, tb = tail_bound(sp, t, v0)
        if not ok or err > 1e-9:
            continue
        tau = tail_length(sp, t, target, tb)
        assert 0.0 < tau <= tb
        tol = err + 8.0 * EPS * (t + tau) + ref_error(p, t_ref)
        assert abs(t + tau - t_ref) <= tol, (t, v0, err)
        if 2.0 * v0 * rate >= 1e-4 * push(p, t):
            long_hops += 1
            if long_hops == 1:
                tau0 = tail_length(sp, t, 2.0 * v0 / (1.0 - p.r), tb)
                assert abs(t + tau0 - t_ref) > 100.0 * tol
        checked += 1
    assert long_hops >= 2 and checked >= 5


@pytest.mark.parametrize("name", [n for n in CHATTERS if n != "c=5"])
def test_run_sums_the_chatter_early_and_ends_where_the_reference_ends(name):
    """In a run the tail is summed at hops at least 10 times longer than TAIL_TOL time
    scales (the fallback threshold), every faster impact is still resolved one by one, and
    the mass comes to rest where the reference's stepped chatter ends.  (Not c = 5: its
    chatter ends at t ~ 2, where the rounding-level tolerance 4 eps t is met only at hops
    ~6 times TAIL_TOL.)"""
    p, t_end = CHATTERS[name]
    R = chatter_reference(name)
    sol = il.simulate(p, t_end=t_end, t_record=0.0)
    assert sol.n_chatter >= 1
    s = sol.sticking[0, 0]
    s_ref = R.chatter_ends[0]
    assert abs(s - R.sticking[0][0]) == abs(s - s_ref)
    before = sol.impacts.t <= s
    t_last, v_last = sol.impacts.t[before][-1], abs(sol.impacts.v[before][-1])
    hop = 2.0 * p.r * v_last / push(p, t_last)
    assert hop * p.rate() >= 10.0 * TAIL_TOL
    X = steady_orbit(p)[2] + abs(p.g)
    assert abs(s - s_ref) <= 8 * EPS * X / ((1 - p.r) * v_last) + ref_error(p, s_ref)
    # ... and to rounding level: the tail's bound is below 4 eps (t + tau) where it is
    # summed, and its start carries the resolved hops' rounding, each impact time timed to
    # 4 eps t (Newton's stopping rule): 64 eps s allows 16 of them.  Measured 0 to 24 eps s;
    # Budd & Dux's sum without the correction term misses by 2e-11 to 2e-10 here.
    assert abs(s - s_ref) <= 64 * EPS * s + ref_error(p, s_ref)
    # the reference's impacts up to the last resolved one, matched one by one
    fast = R.t[R.t <= t_last * (1 + 4 * EPS)]
    np.testing.assert_allclose(sol.impacts.t[before], fast, rtol=0,
                               atol=1e-11 + 8 * EPS * X / v_last)


def test_bound_refuses_where_the_push_turns_outwards_before_the_tail_ends():
    """omega = 0.2, g = 0: the push A = -cos(omega t) falls to zero at 3 pi / (2 omega).
    Rebounding 0.01 before that at v0 = 2e-6, the summed tail would need ~0.01: the bound
    refuses, the impact's outcome is flight, and the run follows the reference's four
    hops and flies off without sticking."""
    p = PAPER.replace(omega=0.2)
    t0 = 1.5 * math.pi / p.omega - 0.01
    v0 = 2e-6
    sp = constants(p)
    assert push(p, t0) > 0
    ok, target, err, tb = tail_bound(sp, t0, v0)
    assert not ok
    mode, tn = impact_outcome(sp, t0, v0, p.rate(), TAIL_TOL, math.inf)
    assert mode == FLY and tn == t0
    R = mp_cached(p, 2000, p.g, v0, t0, t0 + 1.0)
    sol = il.simulate(p, t_end=t0 + 1.0, x0=p.g, v0=v0, t0=t0, t_record=t0)
    assert R.sticking == [] and sol.sticking.size == 0 and sol.n_chatter == 0
    assert sol.impacts.t.size == R.t.size == 4
    # hops resolved by the certified search: impact times to a few ulps of t
    np.testing.assert_allclose(sol.impacts.t, R.t, rtol=0, atol=16 * EPS * t0)


def test_bound_refuses_a_stiff_spring_and_the_run_goes_on_hop_by_hop():
    """The spring's share of each hop, q int y (q = k / m), enters the bound: with
    k = 1e6 and g = 0 (the same push A as k = 1) a rebound the k = 1 system sums at once
    is refused, the run resolves further hops, and its accumulation time still matches
    the reference's stepped chatter."""
    soft = PAPER.replace(omega=0.2)
    stiff = soft.replace(k=1e6)
    t0 = 15.0                        # push -cos(3) ~ 0.99 into the wall
    v0 = 1e-5
    sp_soft, sp_stiff = constants(soft), constants(stiff)
    ok, target, err, tb = tail_bound(sp_soft, t0, v0)
    tau = tail_length(sp_soft, t0, target, tb)
    assert ok and err <= 4 * EPS * (t0 + tau)
    assert impact_outcome(sp_soft, t0, v0, soft.rate(), TAIL_TOL, math.inf)[0] == STICK
    ok, target, err, tb = tail_bound(sp_stiff, t0, v0)
    assert not ok or err > 4 * EPS * (t0 + target / push(stiff, t0))
    assert impact_outcome(sp_stiff, t0, v0, stiff.rate(), TAIL_TOL, math.inf)[0] == FLY
    R = mp_cached(stiff, 5000, stiff.g, v0, t0, t0 + 0.01)
    sol = il.simulate(stiff, t_end=t0 + 0.01, x0=stiff.g, v0=v0, t0=t0, t_record=t0)
    assert R.chatter_ends and sol.n_chatter == 1 and sol.impacts.t.size >= 2
    s, s_ref = sol.sticking[0, 0], R.chatter_ends[0]
    v_last = abs(sol.impacts.v[-1])
    X = steady_orbit(stiff)[2] + abs(stiff.g)
    assert abs(s - s_ref) <= 8 * EPS * X / ((1 - stiff.r) * v_last) + ref_error(stiff, s_ref)
    np.testing.assert_allclose(sol.impacts.t, R.t[:sol.impacts.t.size], rtol=0, atol=16 * EPS * t0)


def test_a_run_ending_inside_a_summable_tail_resolves_its_hops_up_to_the_end():
    """A summed tail reports the mass at rest from its first summed hop on, so a tail is
    summed early only if it ends before the run's next reported state.  omega = 0.2: the
    run to 25 sums its chatter at an impact more than 3e-5 before the accumulation time;
    a run ending 3e-5 before it reports the flight state of the hop in progress, as the
    reference does (rounding model of test_exact_accuracy: a hop of speed v is timed to
    ~eps X / v, so x to 8 eps X and v to 8 eps X A / v)."""
    p, t_end = CHATTERS["omega=0.2"]
    full = il.simulate(p, t_end=t_end, t_record=0.0)
    s_ref = chatter_reference("omega=0.2").chatter_ends[0]
    t_stop = s_ref - 3e-5
    assert full.impacts.t[full.impacts.t <= full.sticking[0, 0]][-1] < t_stop
    R = mp_cached(p, 100_000, t_max=t_stop)
    sol = il.simulate(p, t_end=t_stop, t_record=0.0)
    assert R.reason == "t_max" and R.v_end > 0
    t, x, v, stuck = sol.final
    assert not stuck and sol.impacts.t.size == R.t.size
    X = steady_orbit(p)[2] + abs(p.g)
    assert abs(x - R.x_end) <= 8 * EPS * X
    assert abs(v - R.v_end) <= 8 * EPS * X * push(p, t) / R.v_end


def test_the_cheap_floor_never_exceeds_the_bound():
    """impact_outcome skips tail_bound where tail_floor_terms already exceeds the
    tolerance; that is safe only if the floor is a lower bound of the bound's err, checked
    here over random parameters, times and rebounds (fixed seed)."""
    rng = np.random.default_rng(18)
    n = 0
    for _ in range(20_000):
        m, c = 10 ** rng.uniform(-2, 1), 10 ** rng.uniform(-3, 1) * rng.integers(0, 2)
        k, g = 10 ** rng.uniform(-2, 4) * rng.integers(0, 2), rng.uniform(-1, 1)
        r, om = rng.uniform(0.05, 0.99), 10 ** rng.uniform(-2, 1.5)
        t, v0 = rng.uniform(0, 1e3), 10 ** rng.uniform(-9, -2)
        p = il.Params(m=m, c=c, k=k, g=g, r=r, omega=om)
        a0 = push(p, t)
        if a0 <= 0:
            continue
        ok, target, err, tb = tail_bound(constants(p), t, v0)
        if not ok:
            continue
        low, tb_floor = tail_floor_terms(constants(p), v0, a0)
        assert tb_floor == pytest.approx(tb, rel=1e-12)
        assert low <= err * (1 + 1e-12)
        n += 1
    assert n > 5000
