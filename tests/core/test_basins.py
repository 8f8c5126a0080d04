"""Basins of attraction (issue 9): il.basins and il.iter_basins.

References: the period-1 orbit from scipy.optimize.root on the closed-form residual and
its multipliers by central differences of the closed-form impact map (closed_form_ref,
no impactlib inside); long single simulate() runs of 2000 s classified by classify().
"""
import math

import numpy as np
import pytest

import impactlib as il
from closed_form_ref import multipliers, period1_orbits, section_point

P262 = il.Params(r=0.8, omega=2.62)
XR, VR = (0.0, 1.0), (-1.0, 1.0)
N = (11, 11)       # x and v on steps of 0.1 and 0.2: (0.2, 1.0) and (0, 0) are grid points


@pytest.fixture(scope="module")
def b262():
    return il.basins(P262, XR, VR, n=N)


def _cell(b, x, v):
    return int(np.argmin(np.abs(b.v - v))), int(np.argmin(np.abs(b.x - x)))


def _long_run(p, x0, v0, phase=0.0, t_end=2000.0):
    """The start followed by one plain simulate() run, last 500 s recorded."""
    return il.simulate(p, t_end=phase + t_end, t_record=phase + t_end - 500.0, x0=x0, v0=v0,
                       t0=phase, phase=phase)


def test_grid_and_shapes_follow_the_contract(b262):
    np.testing.assert_array_equal(b262.x, np.linspace(*XR, N[0]))
    np.testing.assert_array_equal(b262.v, np.linspace(*VR, N[1]))
    assert b262.labels.shape == (N[1], N[0]) and b262.labels.dtype.kind == "i"
    assert b262.labels.min() >= -1 and b262.labels.max() < len(b262.attractors)
    assert b262.fractions.shape == (len(b262.attractors),)
    assert math.isclose(b262.fractions.sum() + b262.undecided, 1.0)
    for a in b262.attractors:
        assert a.points.ndim == 2 and a.points.shape[1] == 2
    assert b262.complete


def test_period1_coexists_with_another_attractor_at_2_62(b262):
    """At r = 0.8, omega = 2.62: >= 2 attractors, one the stable 1-impact period-1 orbit
    whose section point is the root of the closed-form period-1 residual."""
    assert len(b262.attractors) >= 2
    orbs = period1_orbits(P262)
    stable = [o for o in orbs if np.all(np.abs(multipliers(P262, *o)) < 1)]
    assert len(stable) == 1
    ref = np.array(section_point(P262, *stable[0], phase=0.0))
    p1 = [a for a in b262.attractors if a.label == "1-impact period-1"]
    assert len(p1) == 1
    a = p1[0]
    assert a.impacts == 1 and a.period == 1 and a.points.shape == (1, 2)
    # settled to 1e-6 of the grid scale; the reported bound must hold (x4 safety, as the
    # comparison of orbits uses)
    err = np.abs(a.points[0] - ref).max()
    assert err <= 2e-6
    assert err <= 4 * a.error
    # the other attractor is the paper's coexisting 3-impact period-3 orbit
    assert any(b.label == "3-impact period-3" and b.points.shape == (3, 2)
               for b in b262.attractors)


def test_start_0_2_1_lands_on_period1_and_rest_does_not(b262):
    lab = {a: b262.attractors[b262.labels[_cell(b262, *a)]].label for a in [(0.2, 1.0), (0.0, 0.0)]}
    assert lab[(0.2, 1.0)] == "1-impact period-1"
    assert lab[(0.0, 0.0)] != "1-impact period-1"
    assert b262.labels[_cell(b262, 0.0, 0.0)] >= 0


def test_cells_agree_with_long_single_runs(b262):
    """Every 7th cell: classify() of a 2000 s run from the start gives the cell's label,
    and the run's last section points are the attractor's points (as sets)."""
    cells = np.argwhere(np.ones_like(b262.labels, dtype=bool))[::7]
    for i, j in cells:
        a = b262.attractors[b262.labels[i, j]]
        sol = _long_run(P262, b262.x[j], b262.v[i])
        assert il.classify(sol).label == a.label, (b262.x[j], b262.v[i])
        k = a.points.shape[0]
        tail = np.column_stack([sol.poincare.x[-k:], sol.poincare.v[-k:]])
        d = np.abs(tail[:, None, :] - a.points[None]).max(axis=-1)
        assert d.min(axis=1).max() < 1e-5 and d.min(axis=0).max() < 1e-5


def test_phase_other_than_zero():
    """Section t = T/3: the cells agree with single runs started at t0 = T/3."""
    ph = P262.T / 3
    b = il.basins(P262, (0.0, 0.6), (-0.8, 0.8), n=(4, 3), phase=ph)
    for i, v in enumerate(b.v):
        for j, x in enumerate(b.x):
            sol = _long_run(P262, x, v, phase=ph)
            assert il.classify(sol).label == b.attractors[b.labels[i, j]].label
    p1 = [a for a in b.attractors if a.label == "1-impact period-1"]
    if p1:
        tau, u = [o for o in period1_orbits(P262)
                  if np.all(np.abs(multipliers(P262, *o)) < 1)][0]
        ref = section_point(P262, tau, u, phase=ph)
        assert np.abs(p1[0].points[0] - ref).max() < 2e-6


def test_period6_at_2_64():
    """The issue's second scene: the 6-impact period-6 orbit coexists with period-1."""
    b = il.basins(P262.replace(omega=2.64), (0.0, 1.0), (-1.5, 1.5), n=(8, 8))
    labels = sorted(a.label for a in b.attractors)
    assert labels == ["1-impact period-1", "6-impact period-6"]
    assert b.undecided == 0


def test_chaotic_attractor_is_one_entry():
    """omega = 2.8 (the paper's Fig. 6): every start on the one chaotic attractor."""
    b = il.basins(il.Params(omega=2.8), (0.0, 1.0), (-1.0, 1.0), n=(3, 3))
    assert len(b.attractors) == 1
    a = b.attractors[0]
    assert a.kind == "chaotic" and a.impacts == math.inf and a.period == math.inf
    assert np.all(b.labels == 0)
    sol = _long_run(il.Params(omega=2.8), 0.5, 0.0)
    assert il.classify(sol).kind == "chaotic"
    x0, x1, v0, v1 = a.box
    assert x0 <= sol.poincare.x.min() + 0.05 and sol.poincare.x.max() <= x1 + 0.05
    assert v0 <= sol.poincare.v.min() + 0.05 and sol.poincare.v.max() <= v1 + 0.05


def test_stream_equals_whole_and_cancels():
    whole = il.basins(P262, XR, VR, n=N)
    got = np.full_like(whole.labels, -7)
    blocks = list(il.iter_basins(P262, XR, VR, n=N, rows_per_block=2))
    assert len(blocks) == 6 and blocks[-1].rows_done == N[1]
    for blk in blocks:
        got[blk.start:blk.start + blk.labels.shape[0]] = blk.labels
    # same attractors (order of discovery may differ only if blocks finish out of order;
    # they are yielded in row order, so indices agree)
    assert [a.label for a in blocks[-1].attractors] == [a.label for a in whole.attractors]
    np.testing.assert_array_equal(got, whole.labels)
    gen = il.iter_basins(P262, XR, VR, n=(11, 40), rows_per_block=1)
    first = next(gen)
    assert first.start == 0 and first.rows_done == 1
    gen.close()        # cancels the blocks queued behind it


def test_time_limit_gives_partial_result():
    b = il.basins(P262, XR, VR, n=(20, 200), time_limit=1e-6)
    assert not b.complete
    assert "time_limit" in b.message
    assert np.all(b.labels[-1] == -1)


@pytest.mark.parametrize("kwargs, field", [
    (dict(x_range=(-0.1, 1.0)), "x_range"),
    (dict(x_range=(0.0, math.nan)), "x_range"),
    (dict(x_range=(1.0, 0.0)), "x_range"),
    (dict(v_range=(0.0, math.inf)), "v_range"),
    (dict(v_range=5.0), "v_range"),
    (dict(n=(0, 5)), "n="),
    (dict(n=(2.5, 3)), "n="),
    (dict(n=(2000, 2000)), "n="),
    (dict(n=True), "n="),
    (dict(phase=-1.0), "phase"),
    (dict(phase=10.0), "phase"),
    (dict(max_periods=5), "max_periods"),
    (dict(time_limit=0.0), "time_limit"),
])
def test_bad_input_names_the_field(kwargs, field):
    args = dict(x_range=XR, v_range=VR, n=(3, 3))
    args.update(kwargs)
    with pytest.raises(ValueError, match=field):
        il.basins(P262, **args)
    with pytest.raises(ValueError, match=field):
        il.iter_basins(P262, **args)


def test_starts_below_a_shifted_wall_are_refused():
    with pytest.raises(ValueError, match=r"x_range.*below the wall g=0.3"):
        il.basins(P262.replace(g=0.3), (0.0, 1.0), VR, n=(3, 3))


def test_no_dissipation_is_said():
    """c = 0, r = 1: the section map preserves area (det = r^2 exp(-2 c T / m) = 1), so
    nothing can attract; the result says so instead of presenting attractors silently."""
    b = il.basins(il.Params(c=0.0, r=1.0, omega=1.0), (0.0, 1.0), (-1.0, 1.0), n=(4, 4),
                  max_periods=200)
    assert "no dissipation" in b.message
    assert b.complete


def test_period1_basin_ends_at_its_period_doubling():
    """The closed-form multiplier of period-1 crosses -1 at omega = 2.6589 (r = 0.8):
    just below, period-1 is among the attractors; just above it is not, and the
    period-2 orbit born there is."""
    from scipy.optimize import brentq

    def f(w):
        p = P262.replace(omega=w)
        mus = [multipliers(p, *o) for o in period1_orbits(p)]
        mu = min(mus, key=lambda m: np.abs(m).max())
        return (mu.real.min() + 1.0) if np.all(np.abs(mu.imag) < 1e-9) else 1.0

    w_pd = brentq(f, 2.64, 2.70, xtol=1e-6)
    below = il.basins(P262.replace(omega=w_pd - 0.009), (0.0, 1.0), (-1.5, 1.5), n=(8, 8))
    above = il.basins(P262.replace(omega=w_pd + 0.011), (0.0, 1.0), (-1.5, 1.5), n=(8, 8))
    assert "1-impact period-1" in [a.label for a in below.attractors]
    assert "1-impact period-1" not in [a.label for a in above.attractors]
    assert "2-impact period-2" in [a.label for a in above.attractors]
