"""Sticking, release, preload and chatter, against closed forms and the mpmath reference."""
import math

import numpy as np
import pytest

import impactlib as il
from impactlib.verify.report import steady_orbit
from impactlib.verify.reference import mp_release_time

from core_helpers import EPS, PAPER, mp_cached


def test_plastic_impacts_stick_until_the_force_turns_outwards():
    p = PAPER.replace(r=0.0)
    sol = il.simulate(p, t_end=60.0, t_record=0.0)
    R = mp_cached(p, 1_000, t_max=60.0)
    assert sol.impacts.t.size == R.t.size > 10
    # every impact (r = 0) starts a sticking interval at once ...
    np.testing.assert_array_equal(sol.sticking[:, 0], sol.impacts.t)
    # ... which ends where cos(w t) crosses zero upwards (the reference's arccos), and no
    # impact happens while stuck
    for (s, e) in sol.sticking:
        if e < 60.0:
            assert e == pytest.approx(mp_release_time(p, s), rel=0, abs=4 * EPS * e)
        assert not np.any((sol.impacts.t > s) & (sol.impacts.t < e))
    np.testing.assert_allclose(sol.impacts.t, R.t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sol.impacts.v, R.v, rtol=0, atol=1e-10)


@pytest.mark.parametrize("k, g", [(1.0, 1.0), (1.0, 1.5), (2.0, 0.5), (4.0, 0.3)])
def test_preload_with_kg_at_least_one_never_leaves(k, g):
    """k g >= 1: the spring's preload beats the largest pull cos = 1; the mass rests on the
    wall for ever (k g = 1 only touches zero force, never a positive one)."""
    if k * g < 1:
        pytest.skip("k g < 1")  # pragma: no cover
    p = PAPER.replace(k=k, g=g)
    for method, kw in [("exact", {}), ("rk4", {"dt": 1e-2}), ("rk45", {})]:
        sol = il.simulate(p, t_end=100.0, t_record=0.0, dense=101, method=method, **kw)
        assert sol.success
        assert sol.impacts.t.size == 0
        np.testing.assert_array_equal(sol.sticking, [[0.0, 100.0]])
        assert np.all(sol.dense.x == g) and np.all(sol.dense.v == 0.0)
        assert sol.final[3] is True


def test_preload_below_one_leaves():
    sol = il.simulate(PAPER.replace(k=4.0, g=0.24), t_end=20.0, t_record=0.0)
    assert sol.impacts.t.size > 0


@pytest.mark.parametrize("g", [0.0, 0.3])
def test_release_leaves_as_tau_cubed_without_a_spurious_impact(g):
    """At release the net force F(t) = cos(w t) - k g is exactly zero, so
    x - g = F'(t_r) tau^3 / (6 m) (1 + K tau + O(tau^2)),  K = (F'' - 2 c F' / m) / (4 F'),
    from Eq. (1) differentiated at rest (x'' = 0, x''' = F'/m, x'''' = (F'' - 2c x''')/m).
    The dense output right after release follows it, and no impact follows for T/8."""
    p = PAPER.replace(r=0.0, g=g)
    first = il.simulate(p, t_end=10.0, t_record=0.0)
    tr = mp_release_time(p, first.sticking[0, 0])
    assert first.sticking[0, 1] == pytest.approx(tr, rel=0, abs=4 * EPS * tr)
    sol = il.simulate(p, t_end=tr + 0.05, t_record=tr, dense=51)
    tau = sol.dense.t[1:] - tr
    w = p.omega
    Fp = -w * math.sin(w * tr)
    Fpp = -w * w * math.cos(w * tr)
    assert Fp > 0
    K = (Fpp - 2 * p.c * Fp / p.m) / (4 * Fp)
    model = Fp * tau ** 3 / (6 * p.m) * (1 + K * tau)
    X = steady_orbit(p)[2] + abs(g)
    # next term of the series (measured coefficient < 0.5 tau^2 relative) plus rounding of x
    assert np.all(np.abs(sol.dense.x[1:] - g - model) <= 2 * tau ** 2 * model + 8 * EPS * X)
    assert np.all(sol.dense.x[1:] > g) and np.all(sol.dense.v[1:] > 0)
    after = il.simulate(p, t_end=tr + p.T / 8, t_record=tr)
    assert after.impacts.t.size == 0


def test_chatter_ends_where_the_stepped_reference_ends():
    """Complete chattering at omega = 0.2: the exact method sums the geometric tail
    (Budd & Dux), the reference steps through every one of its ~150 impacts in mpmath
    until the rebound is below 1e-16.  They agree on where the mass comes to rest, to the
    rounding-amplification model of test_exact_accuracy (here ~5e-9; measured ~2e-9), and
    on the release time to rounding."""
    p = PAPER.replace(omega=0.2)
    R = mp_cached(p, 100_000, t_max=25.0)
    sol = il.simulate(p, t_end=25.0, t_record=0.0)
    assert len(R.sticking) == len(sol.sticking) == 1 and sol.n_chatter == 1
    (s_ref, e_ref), (s, e) = R.sticking[0], sol.sticking[0]
    assert R.chatter_ends == [s_ref]
    v_last = abs(sol.impacts.v[sol.impacts.t <= s][-1])
    X = steady_orbit(p)[2]
    assert abs(s - s_ref) <= 8 * EPS * X / ((1 - p.r) * v_last)
    assert abs(e - e_ref) <= 4 * EPS * e_ref
    # the summed tail hid only slow impacts: every reference impact faster than the last
    # recorded one is matched, to the time a hop of that speed is known in float64
    # (eps X / |v|: up to ~1e-9 at the slowest recorded impacts)
    # (the slowest matched pair itself differs at rounding level: compare with a margin)
    fast = np.abs(R.v) >= v_last * (1 - 1e-6)
    assert fast.sum() == sol.impacts.t.size
    err = np.abs(sol.impacts.t - R.t[fast])
    assert np.all(err <= 1e-11 + 8 * EPS * X / np.abs(R.v[fast]))


def test_chatter_at_most_once_per_period_and_sticks_every_period():
    """omega = 0.2 over the paper's window: one chatter summed and one sticking interval per
    forcing period (complete chattering), each released at the same phase."""
    p = PAPER.replace(omega=0.2)
    sol = il.simulate(p, t_end=500.0, t_record=250.0)
    n_periods = (500.0 - 250.0) / p.T
    assert len(sol.sticking) in (math.floor(n_periods), math.ceil(n_periods))
    assert sol.n_chatter >= math.floor(n_periods) - 1
    released = sol.sticking[:, 1][sol.sticking[:, 1] < 500.0]
    np.testing.assert_allclose(np.mod(released, p.T), np.mod(released[0], p.T), atol=1e-9)
