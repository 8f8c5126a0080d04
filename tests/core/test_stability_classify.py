"""classify earns "chaotic" by a measured exponent; the cases that used to be called
chaotic without one get honest labels."""
import math

import numpy as np
import pytest

import impactlib as il

from core_helpers import PAPER


def benettin(p, t_start, t_stop, every, d0=1e-9):
    """Largest exponent from two nearby runs of il.simulate, renormalised ``every``."""
    sol = il.simulate(p, t_end=t_start, t_record=t_start)
    t, x, v, _ = sol.final
    xb, vb = x + d0, v
    acc = 0.0
    while t < t_stop - 1e-9:
        t1 = t + every
        a = il.simulate(p, t_end=t1, t_record=t1, x0=x, v0=v, t0=t)
        b = il.simulate(p, t_end=t1, t_record=t1, x0=max(xb, p.g), v0=vb, t0=t)
        t, x, v = a.final[:3]
        dx, dv = b.final[1] - x, b.final[2] - v
        d = math.hypot(dx, dv)
        acc += math.log(d / d0)
        xb, vb = x + dx * d0 / d, v + dv * d0 / d
    return acc / (t_stop - t_start)


def test_undamped_elastic_resonance_is_unbounded():
    sol = il.simulate(PAPER.replace(r=1.0, c=0.0, omega=2.0))
    v = np.abs(sol.impacts.v)
    assert v[-1] > 1.5 * v[0]                 # the speed really grows, cycle after cycle
    m = il.classify(sol)
    assert m.kind == "unbounded" and m.label.startswith("unbounded (no dissipation)")


def test_omega_1000_short_window_is_undetermined_long_window_chaotic():
    p = PAPER.replace(omega=1000.0)
    m = il.classify(il.simulate(p))
    assert m.kind == "undetermined" and "lengthen the window" in m.label
    long = il.classify(il.simulate(p, t_end=5000.0, t_record=500.0))
    assert long.kind == "chaotic" and long.lyapunov > 2 * long.lyapunov_error
    # two nearby exact runs separate at the same rate
    assert long.lyapunov == pytest.approx(benettin(p, 5000.0, 9500.0, 1.0), abs=0.02)


def test_coarse_rk45_is_not_called_chaotic():
    sol = il.simulate(PAPER, method="rk45", rtol=1e-2)
    m = il.classify(sol)
    assert m.kind == "undetermined" and "too coarse" in m.label
    orb = il.periodic_orbit(PAPER)
    assert m.lyapunov == pytest.approx(math.log(abs(orb.multipliers[0])) / PAPER.T, abs=0.01)


def test_chaos_is_measured():
    m = il.classify(il.simulate(PAPER.replace(omega=2.8)))
    assert m.kind == "chaotic" and m.label == "chaotic (∞-impact period-∞)"
    assert m.lyapunov > 2 * m.lyapunov_error > 0
