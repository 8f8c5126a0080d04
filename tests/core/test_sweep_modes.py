"""Sweep modes of issue 9: hysteresis, the regime map, diagrams in r and g.

References: the period-doubling frequency at r = 0.6 where a multiplier of the period-1
orbit (scipy.optimize.root on the closed-form residual, central differences of the
closed-form impact map; closed_form_ref) crosses -1, located by brentq; single
simulate() runs for spot values; classify() of single runs for the regime map.
"""
import numpy as np
import pytest
from scipy.optimize import brentq

import impactlib as il
from closed_form_ref import multipliers, period1_orbits

from core_helpers import PAPER

T_END, T_REC = 500.0, 250.0


def clusters(v, gap=1e-3):
    """Distinct impact velocities: groups separated by more than ``gap``."""
    v = np.sort(np.asarray(v))
    return 0 if v.size == 0 else 1 + int(np.sum(np.diff(v) > gap))


def test_up_and_down_sweeps_differ_at_r_0_8():
    """Hysteresis on [2.5, 2.8]: continuation up (from period-1) and down (from chaos)
    keep different attractors somewhere: at some omega one direction sits on a periodic
    orbit (at most 8 distinct impact velocities) and the other does not, and a window
    four times longer keeps it so (coexistence, not a slow transient)."""
    ws = np.round(np.linspace(2.5, 2.8, 31), 3)
    bif = il.bifurcation(PAPER, "omega", ws, t_end=T_END, t_record=T_REC, warm_start="both")
    differ = []
    for i, w in enumerate(ws):
        up = bif.v[(bif.index == i) & (bif.direction == 1)]
        dn = bif.v[(bif.index == i) & (bif.direction == -1)]
        if clusters(up) != clusters(dn) and min(clusters(up), clusters(dn)) <= 8:
            differ.append(w)
    assert differ, "up and down sweeps gave the same impact sets everywhere"
    long = il.bifurcation(PAPER, "omega", ws, t_end=4 * T_END, t_record=4 * T_REC,
                          warm_start="both")
    for w in differ:
        i = int(np.nonzero(ws == w)[0][0])
        up = long.v[(long.index == i) & (long.direction == 1)]
        dn = long.v[(long.index == i) & (long.direction == -1)]
        assert clusters(up) != clusters(dn), w


def test_coexistence_shows_between_continuation_and_rest():
    """At omega = 2.62 the sweep from below stays on period-1; a start from rest lands on
    the 3-impact period-3 orbit (the coexistence the basins show)."""
    ws = np.round(np.linspace(2.5, 2.62, 13), 3)
    up = il.bifurcation(PAPER, "omega", ws, t_end=T_END, t_record=T_REC, warm_start="up")
    assert clusters(up.v[up.index == ws.size - 1]) == 1
    rest = il.simulate(PAPER.replace(omega=2.62), t_end=T_END, t_record=T_REC)
    assert il.classify(rest).label == "3-impact period-3"


def test_independent_starts_reproduce_single_runs():
    ws = np.array([2.5, 2.6, 2.64, 2.7, 2.8])
    bif = il.bifurcation(PAPER, "omega", ws, t_end=T_END, t_record=T_REC)
    assert np.all(bif.direction == 0)
    for i, w in enumerate(ws):
        sol = il.simulate(PAPER.replace(omega=w), t_end=T_END, t_record=T_REC)
        np.testing.assert_array_equal(bif.v[bif.index == i], sol.impacts.v)
        np.testing.assert_array_equal(bif.t[bif.index == i], sol.impacts.t)


def test_regime_map_agrees_with_classify_at_random_cells():
    """The paper's window (omega in [0.1, 5], r in [0, 0.9]) at the paper's defaults:
    20 random cells of a 40 x 10 map, each against classify() of its own single run."""
    ws = np.linspace(0.1, 5.0, 40)
    rs = np.linspace(0.0, 0.9, 10)
    rm = il.regime_map(PAPER, "omega", ws, "r", rs, t_end=T_END, t_record=T_REC)
    rng = np.random.default_rng(9)
    cells = rng.choice(ws.size * rs.size, size=20, replace=False)
    for c in cells:
        iy, ix = divmod(int(c), ws.size)
        sol = il.simulate(PAPER.replace(omega=ws[ix], r=rs[iy]), t_end=T_END, t_record=T_REC)
        assert rm.label(iy, ix) == il.classify(sol).label, (ws[ix], rs[iy])


def test_regime_map_judges_every_aperiodic_cell_as_classify_does():
    """Cells whose points never repeat are judged from the sweep's own run of the cell
    (its final state and work): each verdict, Lyapunov exponent and error included, must
    be classify()'s of the cell's single simulate() run.  Then a row without dissipation
    (c = 0, r = 1), where the growth check needs every impact and the cell is run again."""
    ws = np.linspace(3.0, 5.0, 24)
    rs = np.linspace(0.3, 0.9, 6)
    rm = il.regime_map(PAPER, "omega", ws, "r", rs, t_end=T_END, t_record=T_REC)
    kinds = {mo.kind for mo in rm.motions.values()}
    assert len(rm.motions) >= 10 and {"chaotic", "not settled", "undetermined"} <= kinds
    for (iy, ix), mo in rm.motions.items():
        sol = il.simulate(PAPER.replace(omega=ws[ix], r=rs[iy]), t_end=T_END, t_record=T_REC)
        assert repr(mo) == repr(il.classify(sol)), (ws[ix], rs[iy])
    p = PAPER.replace(c=0.0)
    ws = np.linspace(0.5, 4.0, 12)
    rm = il.regime_map(p, "omega", ws, "r", [1.0], t_end=200.0, t_record=100.0)
    assert rm.motions
    for (iy, ix), mo in rm.motions.items():
        sol = il.simulate(p.replace(omega=ws[ix], r=1.0), t_end=200.0, t_record=100.0)
        assert repr(mo) == repr(il.classify(sol)), ws[ix]


@pytest.fixture(scope="module")
def omega_pd():
    """Period doubling of the period-1 orbit at r = 0.6: a real multiplier through -1."""
    def f(w):
        p = PAPER.replace(r=0.6, omega=w)
        (orb,) = period1_orbits(p)
        mu = multipliers(p, *orb)
        assert np.all(np.abs(mu.imag) < 1e-9) or np.all(np.abs(mu) < 1)
        return (min(mu.real) + 1.0) if np.all(np.abs(mu.imag) < 1e-9) else 1.0
    return brentq(f, 2.6, 2.7, xtol=1e-7)


def test_period_doubling_at_r_0_6(omega_pd):
    """The regime map and the diagram change from 1-impact period-1 to 2-impact
    period-2 where the closed-form multiplier crosses -1 (2.6685; the paper reads 2.6).
    Within 0.015 of it the transient (multiplier near -1) is too slow to judge."""
    assert 2.65 < omega_pd < 2.69
    ws = np.concatenate([np.linspace(omega_pd - 0.1, omega_pd - 0.015, 6),
                         np.linspace(omega_pd + 0.015, omega_pd + 0.06, 4)])
    p = PAPER.replace(r=0.6)
    rm = il.regime_map(p, "omega", ws, "r", [0.6], t_end=T_END, t_record=T_REC)
    bif = il.bifurcation(p, "omega", ws, t_end=T_END, t_record=T_REC)
    for i, w in enumerate(ws):
        below = w < omega_pd
        assert rm.label(0, i) == ("1-impact period-1" if below else "2-impact period-2"), w
        assert clusters(bif.v[bif.index == i]) == (1 if below else 2), w


@pytest.mark.parametrize("name, values, base", [
    ("r", [0.0, 0.3, 0.6, 0.9, 1.0], PAPER),
    ("g", [-0.5, -0.1, 0.0, 0.2, 0.5], PAPER),
    ("c", [0.0, 0.02, 0.2], PAPER),
    ("m", [0.5, 1.0, 2.0], PAPER),
    ("k", [0.0, 0.5, 2.0], PAPER),
])
def test_diagram_in_any_parameter_equals_single_runs(name, values, base):
    """A diagram in r at omega = 2 (and in g, c, m, k): each value's impacts are those of
    a single simulate() run with that parameter (starting from rest on the wall, x0 =
    max(0, g))."""
    bif = il.bifurcation(base, name, values, t_end=T_END, t_record=T_REC)
    assert bif.name == name
    for i, val in enumerate(values):
        sol = il.simulate(base.replace(**{name: val}), t_end=T_END, t_record=T_REC)
        rows = bif.index == i
        np.testing.assert_array_equal(bif.param[rows], val)
        np.testing.assert_array_equal(bif.v[rows], sol.impacts.v)
        np.testing.assert_array_equal(bif.t[rows], sol.impacts.t)
        assert bif.n_impacts[i] == sol.impacts.t.size or bif.status[i] == 3


def test_diagram_in_r_warm_start_both_directions():
    """Continuation in r at omega = 2: the up run's first value is the cold run."""
    rs = np.linspace(0.2, 0.9, 8)
    bif = il.bifurcation(PAPER, "r", rs, t_end=T_END, t_record=T_REC, warm_start="both")
    sol = il.simulate(PAPER.replace(r=0.2), t_end=T_END, t_record=T_REC)
    np.testing.assert_array_equal(bif.v[(bif.index == 0) & (bif.direction == 1)], sol.impacts.v)
    sol = il.simulate(PAPER.replace(r=0.9), t_end=T_END, t_record=T_REC)
    np.testing.assert_array_equal(bif.v[(bif.index == 7) & (bif.direction == -1)], sol.impacts.v)


def test_regime_map_cell_with_plastic_impacts_is_judged_without_warnings():
    """r = 0, omega = 4.834: the points never repeat, so classify measures the Lyapunov
    exponents; with r = 0 every impact's saltation matrix is singular (det = r^2 = 0), so
    an exponent can be -inf, and its error estimate must not turn into NaN warnings
    (which pytest raises as errors here)."""
    sol = il.simulate(PAPER.replace(omega=4.8338983050847455, r=0.0), t_end=T_END,
                      t_record=T_REC)
    mo = il.classify(sol)
    assert mo.kind in ("chaotic", "not settled", "undetermined")
    rm = il.regime_map(PAPER, "omega", [4.8338983050847455], "r", [0.0], t_end=T_END,
                       t_record=T_REC)
    assert rm.label(0, 0) == mo.label
