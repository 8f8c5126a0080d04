"""Lyapunov exponents through impacts, against independent references: the Floquet
multiplier of the periodic orbit, the exact determinant identity (sum rule), and a
two-trajectory (Benettin) estimate from the exact simulator alone."""
import math

import numpy as np
import pytest

import impactlib as il
from impactlib.kernels import engine as E
from impactlib.simulate import run_constants

from core_helpers import PAPER


def benettin(p, t_start, t_stop, d0=1e-9):
    """Largest exponent from two nearby trajectories of il.simulate, the separation
    renormalised to d0 every forcing period (no tangent dynamics involved)."""
    sol = il.simulate(p, t_end=t_start, t_record=t_start)
    t, x, v, _ = sol.final
    xb, vb = x + d0, v
    acc = 0.0
    while t < t_stop - 1e-9:
        t1 = t + p.T
        a = il.simulate(p, t_end=t1, t_record=t1, x0=x, v0=v, t0=t)
        b = il.simulate(p, t_end=t1, t_record=t1, x0=max(xb, p.g), v0=vb, t0=t)
        t, x, v = a.final[:3]
        dx, dv = b.final[1] - x, b.final[2] - v
        d = math.hypot(dx, dv)
        acc += math.log(d / d0)
        xb, vb = x + dx * d0 / d, v + dv * d0 / d
    return acc / (t_stop - t_start)


def sum_rule(p, ly):
    return -2 * p.c / p.m + 2 * ly.nu * math.log(p.r)


def test_periodic_exponent_equals_floquet_multiplier():
    ly = il.lyapunov(PAPER, t_end=5000.0, t_record=500.0)
    orb = il.periodic_orbit(PAPER)
    ref = np.log(np.abs(orb.multipliers)) / PAPER.T
    assert ly.exponents[0] == pytest.approx(ref[0], abs=1e-3)
    assert ly.exponents[1] == pytest.approx(ref[1], abs=1e-3)
    assert ly.n_impacts == pytest.approx(4500.0 / PAPER.T, abs=1)


@pytest.mark.parametrize("omega", [2.0, 1.2, 2.8])
def test_sum_rule(omega):
    p = PAPER.replace(omega=omega)
    ly = il.lyapunov(p, t_end=3000.0, t_record=500.0)
    assert np.all(np.isfinite(ly.exponents))
    assert ly.nu == ly.n_impacts / 2500.0
    assert ly.exponents.sum() == pytest.approx(sum_rule(p, ly), abs=1e-8)


def test_chaotic_exponent_positive_and_matches_benettin():
    p = PAPER.replace(omega=2.8)
    ly = il.lyapunov(p, t_end=5000.0, t_record=500.0)
    assert ly.exponents[0] > 10 * ly.error[0] > 0
    ref = benettin(p, 500.0, 5000.0)
    # two estimates of one number over the same window, along trajectories that part in
    # the chaos: each spreads by about ly.error, their difference by sqrt(2) times that
    assert ly.exponents[0] == pytest.approx(ref, abs=3 * math.sqrt(2) * ly.error[0])


def test_sticking_gives_minus_infinity():
    ly = il.lyapunov(PAPER.replace(omega=0.2), t_end=1000.0, t_record=250.0)
    assert ly.sticks and np.all(ly.exponents == -math.inf)


def test_undamped_elastic_resonance_is_unbounded_not_an_exponent():
    ly = il.lyapunov(PAPER.replace(c=0.0, r=1.0), t_end=500.0, t_record=250.0)
    assert ly.unbounded and np.all(np.isnan(ly.exponents))


def test_bifurcation_strip_same_rows_and_exponents():
    p = PAPER
    w = [0.2, 2.0, 2.8]
    plain = il.bifurcation(p, "omega", w, t_end=1500.0, t_record=250.0)
    bif = il.bifurcation(p, "omega", w, t_end=1500.0, t_record=250.0, lyapunov=True)
    np.testing.assert_array_equal(bif.v, plain.v)
    np.testing.assert_array_equal(bif.t, plain.t)
    assert plain.lyapunov is None and bif.values.shape == bif.lyapunov.shape
    assert bif.lyapunov[0] == -math.inf
    orb = il.periodic_orbit(p)
    assert bif.lyapunov[1] == pytest.approx(math.log(abs(orb.multipliers[0])) / p.T, abs=5e-3)
    assert bif.lyapunov[2] > 0.05
    und = il.bifurcation(p.replace(c=0.0, r=1.0), "omega", [2.0], lyapunov=True)
    assert np.isnan(und.lyapunov[0])


def test_bifurcation_strip_warm_start_rows_unchanged():
    w = [2.0, 2.5, 2.8]
    for warm in ("up", "both"):
        plain = il.bifurcation(PAPER, "omega", w, t_end=300.0, t_record=150.0, warm_start=warm)
        bif = il.bifurcation(PAPER, "omega", w, t_end=300.0, t_record=150.0, warm_start=warm,
                             lyapunov=True)
        np.testing.assert_array_equal(bif.v, plain.v)
        np.testing.assert_array_equal(bif.direction, plain.direction)
        assert np.all(np.isfinite(bif.lyapunov)) and bif.lyapunov[0] < 0


@pytest.mark.parametrize("call, field", [
    (lambda: il.lyapunov(PAPER, t_end=100.0, t_record=100.0), "t_record"),
    (lambda: il.lyapunov(PAPER, x0=math.nan), "x0"),
    (lambda: il.bifurcation(PAPER, "omega", [2.0], method="rk4", dt=0.01, lyapunov=True), "method"),
])
def test_bad_lyapunov_input_names_the_field(call, field):
    with pytest.raises(ValueError, match=field):
        call()


def _window_logs(p, mode, marks, t_end):
    sp, rate, hmax = run_constants(p)
    logs = np.zeros((marks.size - 1, 2))
    ctl = E.controls(t_end, marks[0], hmax, rate, 0.0, 0.0, 0.0, 1e6, 10**8, E.EXACT, mode)
    res = np.empty(E.NRES)
    E.run_engine(sp, ctl, 0.0, max(0.0, p.g), 0.0, E.buffers(marks=marks, logs=logs), res)
    return logs, res


@pytest.mark.parametrize("omega, r", [(2.0, 0.8), (2.8, 0.8), (1.2, 0.8), (4.0, 0.3)])
def test_leading_column_logs_are_the_qr_sums(omega, r):
    """The diagram strip's bookkeeping (engine.LEADING: J's first column, rescaled by
    powers of 2, and |det J| from its closed form) against QR steps at every impact
    (QR_MARKS): the same window logs to rounding, in every window, for periodic and
    chaotic motions.  log|R22| comes from the determinant in one and from the QR
    steps in the other, so a wrong determinant (a missed impact, the damping's sign)
    shows."""
    p = PAPER.replace(omega=omega, r=r)
    marks = np.linspace(200.0, 600.0, 5)
    qr, res_qr = _window_logs(p, E.QR_MARKS, marks, 650.0)
    lead, res_lead = _window_logs(p, E.LEADING, marks, 650.0)
    assert res_qr[1] == res_lead[1] and res_qr[2] == res_lead[2]       # the same run
    scale = np.abs(qr).max(axis=1, keepdims=True) + 1.0
    np.testing.assert_allclose(lead, qr, rtol=0, atol=1e-12 * scale.max())
