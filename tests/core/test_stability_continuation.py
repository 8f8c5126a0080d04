"""Branches of periodic orbits and their events, against independent references: the
exact simulator (orbits return after n periods; multipliers by central differences of
its map on both sides of each event), the determinant identity, and the closed-form
amplitude of the non-impacting orbit for the grazing."""
import math

import numpy as np
import pytest

import impactlib as il

from core_helpers import PAPER


def fd_multipliers(p, x, v, n, h=1e-6):
    def f(x, v):
        sol = il.simulate(p, t_end=n * p.T, t_record=n * p.T, x0=x, v0=v)
        return np.array(sol.final[1:3])
    J = np.column_stack([(f(x + h, v) - f(x - h, v)) / (2 * h),
                         (f(x, v + h) - f(x, v - h)) / (2 * h)])
    mu = np.linalg.eigvals(J)
    return mu[np.argsort(-np.abs(mu))]


def orbit_near(event, name, offset, n=1):
    q = event.params.replace(**{name: event.value + offset})
    orb = il.periodic_orbit(q, n, x0=event.x, v0=event.v)
    assert orb.converged
    return q, orb


def assert_crossing(event, name, through, d=2e-6, n=1):
    """FD multipliers of the simulator a distance d either side of the event: one real
    multiplier is on opposite sides of ``through`` (-1 or +1)."""
    side = []
    for off in (-d, d):
        q, orb = orbit_near(event, name, off, n)
        mu = fd_multipliers(q, orb.x, orb.v, n)
        k = np.argmin(np.abs(mu - through))
        assert abs(mu[k].imag) < 1e-9
        side.append(mu[k].real - through)
    assert side[0] * side[1] < 0


def determinant(p, m, n):
    return p.r ** (2 * m) * math.exp(-2 * p.c * n * p.T / p.m)


@pytest.fixture(scope="module")
def r06():
    return il.continuation(PAPER.replace(r=0.6), "omega", 3.0)


def test_r06_period_doubling_near_267_located(r06):
    pd = [e for e in r06.events if e[0] == "period-doubling"]
    assert len(pd) == 1 and pd[0].value == pytest.approx(2.67, abs=0.02)
    assert_crossing(pd[0], "omega", -1.0)
    # at the located point the simulator's map has the multiplier -1 itself
    mu = fd_multipliers(pd[0].params, pd[0].x, pd[0].v, 1)
    assert np.min(np.abs(mu + 1)) < 1e-5
    # stable before, unstable after
    i = pd[0].index
    assert r06.stable[i - 1] and not r06.stable[i + 1]


def test_doubled_branch_continues_from_the_period_doubling(r06):
    e = next(e for e in r06.events if e.kind == "period-doubling")
    br2 = il.continuation(e.params, "omega", 3.0, n=2, x0=e.x, v0=e.v)
    assert br2.n == 2 and br2.impacts == 2 and len(br2.param) > 10
    # a genuine period-2 orbit of the simulator, stable just after the doubling
    k = np.argmax(br2.param > e.value + 0.02)
    q = e.params.replace(omega=br2.param[k])
    one = il.simulate(q, t_end=q.T, t_record=q.T, x0=br2.x[k], v0=br2.v[k])
    two = il.simulate(q, t_end=2 * q.T, t_record=0.0, x0=br2.x[k], v0=br2.v[k])
    assert np.hypot(one.final[1] - br2.x[k], one.final[2] - br2.v[k]) > 1e-3
    assert two.final[1:3] == pytest.approx((br2.x[k], br2.v[k]), abs=1e-9)
    assert len(two.impacts) == 2 and br2.stable[k]
    np.testing.assert_allclose(br2.multipliers[k], fd_multipliers(q, br2.x[k], br2.v[k], 2),
                               atol=1e-6)


def test_r08_every_stability_change_on_1_to_5_is_an_event():
    up = il.continuation(PAPER, "omega", 5.0)
    down = il.continuation(PAPER, "omega", 1.0)
    events = up.events + down.events
    for br in (up, down):
        assert np.all(np.isfinite(br.param))
        # every change of stability along the branch has an event between the points
        for i in np.flatnonzero(br.stable[1:] != br.stable[:-1]):
            lo, hi = sorted((br.param[i], br.param[i + 1]))
            assert any(lo - 1e-9 <= e.value <= hi + 1e-9 and e.kind != "grazing" for e in events)
        # the determinant identity at every point
        dets = np.abs(np.prod(br.multipliers, axis=1))
        ref = [determinant(PAPER.replace(omega=w), 1, 1) for w in br.param]
        finite = br.admissible
        np.testing.assert_allclose(dets[finite], np.array(ref)[finite], rtol=1e-10)
    pds = sorted(e.value for e in events if e.kind == "period-doubling")
    assert len(pds) >= 3          # loses stability at both ends of [1.04, 2.66], regains below
    # an independent scan: Newton on the stroboscopic map from omega = 2 on a grid, warm
    # started; each change of stability on the 1-impact orbit is one of the events
    for grid in (np.arange(2.0, 5.0, 0.01), np.arange(2.0, 1.03, -0.01)):
        x, v, prev = None, None, None
        for w in grid:
            orb = il.periodic_orbit(PAPER.replace(omega=w), 1, x0=x, v0=v)
            assert orb.converged and orb.impacts == 1
            if prev is not None and orb.stable != prev:
                assert any(min(w, w_prev) <= e <= max(w, w_prev) for e in pds)
            x, v, prev, w_prev = orb.x, orb.v, orb.stable, w
    for e in events:
        if e.kind == "period-doubling" and e.value > 1.03:
            assert_crossing(e, "omega", -1.0)


def test_grazing_demo_saddle_node_then_grazing_at_the_closed_form_amplitude():
    p = PAPER.replace(omega=1.0, c=0.05, r=0.8, g=-5.0)
    amplitude = 1 / math.sqrt((p.k - p.m * p.omega ** 2) ** 2 + (2 * p.c * p.omega) ** 2)
    assert amplitude == pytest.approx(10.0)
    br = il.continuation(p, "g", -10.5)
    kinds = [e.kind for e in br.events]
    assert kinds == ["saddle-node", "grazing"]
    sn, gr = br.events
    # the fold just past the grazing value, where the branch turns back
    assert -amplitude - 0.05 < sn.value < -amplitude
    assert sn.value == pytest.approx(br.param.min(), abs=1e-9)
    # at the located fold the simulator's map has the multiplier +1 (finite differences;
    # the impact speed there is 0.04, so the map's curvature ~ 1/v^3 calls for a small step:
    # truncation ~1e-6, rounding ~1e-16 * 10 / h ~ 3e-8)
    mu = fd_multipliers(sn.params, sn.x, sn.v, 1, h=3e-8)
    assert np.min(np.abs(mu - 1)) < 2e-5
    assert gr.value == pytest.approx(-amplitude, abs=1e-4)
    assert br.stable[sn.index - 1] and not br.stable[sn.index + 1]
    assert br.impact_velocities[-1, 0] == pytest.approx(0.0, abs=1e-6)
    assert not br.admissible[-1] or abs(br.impact_velocities[-1, 0]) < 1e-9


def test_branch_points_are_orbits_of_the_simulator():
    br = il.continuation(PAPER.replace(r=0.6), "omega", 2.5)
    for k in (0, len(br.param) // 2, len(br.param) - 1):
        q = PAPER.replace(r=0.6, omega=br.param[k])
        sol = il.simulate(q, t_end=q.T, t_record=0.0, x0=br.x[k], v0=br.v[k])
        assert sol.final[1:3] == pytest.approx((br.x[k], br.v[k]), abs=1e-9)
        assert len(sol.impacts) == 1
        np.testing.assert_allclose(br.multipliers[k], fd_multipliers(q, br.x[k], br.v[k], 1),
                                   atol=1e-6)


@pytest.mark.parametrize("kwargs, field", [
    (dict(name="omegaa", stop=3.0), "name="), (dict(name="omega", stop=3.0, n=0), "n="),
    (dict(name="omega", stop=3.0, x0=math.inf, v0=0.0), "x0="),
    (dict(name="omega", stop=2.0), "stop="), (dict(name="omega", stop=math.nan), "stop="),
])
def test_bad_branch_input_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        il.continuation(PAPER, **kwargs)


def test_sticking_start_is_a_result_not_an_error():
    br = il.continuation(PAPER.replace(omega=0.2), "omega", 0.3)
    assert len(br.param) == 0 and "sticks" in br.message
