"""Sweeps give exactly what individual simulate() runs give."""
import math

import numpy as np
import pytest

import impactlib as il

from core_helpers import PAPER

OMEGAS = np.array([0.7, 1.2, 2.0, 2.8, 3.5])


@pytest.mark.parametrize("workers", [1, 2])
def test_bifurcation_equals_individual_runs(workers):
    bif = il.bifurcation(PAPER, "omega", OMEGAS, t_end=300.0, t_record=150.0, workers=workers)
    assert np.all(bif.status == 0)
    for i, w in enumerate(OMEGAS):
        sol = il.simulate(PAPER.replace(omega=w), t_end=300.0, t_record=150.0)
        rows = bif.index == i
        assert bif.n_impacts[i] == sol.impacts.t.size == rows.sum()
        np.testing.assert_array_equal(bif.t[rows], sol.impacts.t)
        np.testing.assert_array_equal(bif.v[rows], sol.impacts.v)
        np.testing.assert_array_equal(bif.param[rows], w)
        np.testing.assert_allclose(bif.phase[rows], sol.impacts.phase, rtol=0, atol=1e-12)


def test_bifurcation_over_g_starts_each_run_on_its_own_wall():
    gs = np.array([-0.2, 0.0, 0.3, 0.6])
    bif = il.bifurcation(PAPER, "g", gs, t_end=200.0, t_record=100.0)
    for i, g in enumerate(gs):
        sol = il.simulate(PAPER.replace(g=g), t_end=200.0, t_record=100.0)   # x0 = max(0, g)
        np.testing.assert_array_equal(bif.v[bif.index == i], sol.impacts.v)


def test_warm_start_continues_from_the_previous_final_state():
    """warm_start='up': value i starts where value i-1 ended, at the time t0 in [0, T_i)
    where the forcing has the phase the previous run ended with."""
    vals = np.array([2.0, 2.2, 2.4])
    t_end, t_rec = 200.0, 100.0
    bif = il.bifurcation(PAPER, "omega", vals, t_end=t_end, t_record=t_rec, warm_start="up")
    assert np.all(bif.direction == 1)
    x, v, t_prev, w_prev = 0.0, 0.0, None, None
    for i, w in enumerate(vals):
        t0 = 0.0
        if t_prev is not None:
            ph = math.fmod(w_prev * t_prev, 2 * math.pi)
            t0 = ph / w
        sol = il.simulate(PAPER.replace(omega=w), t_end=t0 + t_end, t_record=t0 + t_rec,
                          x0=x, v0=v, t0=t0)
        rows = bif.index == i
        np.testing.assert_allclose(bif.t[rows], sol.impacts.t, rtol=0, atol=1e-9)
        np.testing.assert_allclose(bif.v[rows], sol.impacts.v, rtol=0, atol=1e-9)
        t_prev, x, v, _ = sol.final
        w_prev = w
    # and differs from independent starts (it continues, it does not restart)
    cold = il.bifurcation(PAPER, "omega", vals, t_end=t_end, t_record=t_rec)
    assert not np.array_equal(cold.t[cold.index == 2], bif.t[bif.index == 2])


def test_warm_start_both_directions_tag_rows():
    bif = il.bifurcation(PAPER, "omega", [2.0, 2.5, 3.0], t_end=100.0, t_record=50.0,
                         warm_start="both")
    assert set(np.unique(bif.direction)) == {-1, 1}
    up = il.bifurcation(PAPER, "omega", [2.0, 2.5, 3.0], t_end=100.0, t_record=50.0,
                        warm_start="up")
    np.testing.assert_array_equal(bif.v[bif.direction == 1], up.v)


def test_regime_map_equals_classify_of_individual_runs():
    ws = [0.2, 1.2, 2.0]
    rs = [0.6, 0.8]
    rm = il.regime_map(PAPER, "omega", ws, "r", rs, t_end=500.0, t_record=250.0)
    assert rm.impacts.shape == (2, 3)
    for iy, r in enumerate(rs):
        for ix, w in enumerate(ws):
            sol = il.simulate(PAPER.replace(omega=w, r=r), t_end=500.0, t_record=250.0)
            assert rm.label(iy, ix) == il.classify(sol).label
    assert rm.label(1, 2) == "1-impact period-1"
    assert rm.label(1, 0).startswith("complete chattering")


def test_iter_bifurcation_chunks_equal_one_run():
    whole = il.bifurcation(PAPER, "omega", OMEGAS, t_end=100.0, t_record=50.0)
    parts = list(il.iter_bifurcation(PAPER, "omega", OMEGAS, chunk=2, t_end=100.0,
                                     t_record=50.0))
    assert len(parts) == 3
    np.testing.assert_array_equal(np.concatenate([b.v for b in parts]), whole.v)
