"""The references themselves, checked against textbook formulas and against each other.

These checks keep the references honest: the mpmath closed form is compared with the
solutions written out independently below (numpy, real arithmetic), and the mpmath
impacts with scipy's DOP853 where both apply.
"""
import math

import numpy as np
import pytest

import impactlib as il
from impactlib.verify.compare import match_impacts
from impactlib.verify.report import CASE_BY_NAME, ivp_reference, reference, steady_orbit
from impactlib.verify.reference import ReferenceNotApplicable, ivp_impacts, mp_release_time, mp_state

from core_helpers import EPS, PAPER, mp_cached

TS = np.linspace(0.0, 30.0, 61)


def textbook(p, x0, v0, t):
    """Free flight written from the textbook (real forms, particular solution by undetermined
    coefficients), vectorised in numpy: an independent formulation of Eq. (1)."""
    m, c, k, w = p.m, p.c, p.k, p.omega
    if c == 0 and k == m * w * w:
        xp = lambda s: s * np.sin(w * s) / (2 * m * w)                    # noqa: E731
        vp0 = 0.0
        xp0 = 0.0
    else:
        d = (k - m * w * w) ** 2 + (2 * c * w) ** 2
        P, Q = (k - m * w * w) / d, 2 * c * w / d
        xp = lambda s: P * np.cos(w * s) + Q * np.sin(w * s)              # noqa: E731
        xp0, vp0 = P, w * Q
    a, w0sq = c / m, k / m
    h0, hv0 = x0 - xp0, v0 - vp0
    if a * a < w0sq:
        b = math.sqrt(w0sq - a * a)
        h = np.exp(-a * t) * (h0 * np.cos(b * t) + (hv0 + a * h0) / b * np.sin(b * t))
    elif a * a == w0sq:
        h = np.exp(-a * t) * (h0 + (hv0 + a * h0) * t)
    else:
        b = math.sqrt(a * a - w0sq)
        l1, l2 = -a + b, -a - b
        A = (hv0 - l2 * h0) / (l1 - l2)
        h = A * np.exp(l1 * t) + (h0 - A) * np.exp(l2 * t)
    return h + xp(t)


@pytest.mark.parametrize("p", [
    PAPER,                                      # underdamped
    PAPER.replace(c=1.0),                       # critical (c^2 = k m exactly)
    PAPER.replace(c=2.0),                       # overdamped
    PAPER.replace(c=0.0, omega=1.0),            # exact resonance
    PAPER.replace(c=0.0, k=0.0),                # free mass, repeated root 0
    PAPER.replace(m=2.0, c=0.3, k=5.0, omega=0.7),
], ids=["under", "critical", "over", "resonance", "k=0,c=0", "other"])
def test_mp_closed_form_matches_textbook(p):
    x_mp, _ = mp_state(p, TS, x0=0.3, v0=-0.2)
    x_tb = textbook(p, 0.3, -0.2, TS)
    scale = np.max(np.abs(x_tb))
    # the textbook form in float64 is good to ~100 eps of the largest term over t <= 30
    assert np.max(np.abs(x_mp - x_tb)) <= 1e-13 * max(scale, 1.0)


def test_resonance_from_rest_is_t_sin_t_over_2():
    p = PAPER.replace(c=0.0, omega=1.0, g=-1e3)
    x, v = mp_state(p, TS, x0=0.0, v0=0.0)
    np.testing.assert_allclose(x, TS * np.sin(TS) / 2, rtol=0, atol=4 * EPS * 15)
    np.testing.assert_allclose(v, (np.sin(TS) + TS * np.cos(TS)) / 2, rtol=0, atol=4 * EPS * 15)


def test_near_critical_has_no_cancellation_in_the_reference():
    """c = 1 +- 1e-9 differs from c = 1 by O(1e-9 t) in x, smoothly: the mpmath form with
    nearly equal roots (l1 - l2 ~ 1e-4) loses ~5 of its 40 digits, not 9 of 16."""
    xc, _ = mp_state(PAPER.replace(c=1.0), TS, x0=0.3, v0=-0.2)
    xp, _ = mp_state(PAPER.replace(c=1.0 + 1e-9), TS, x0=0.3, v0=-0.2)
    xm, _ = mp_state(PAPER.replace(c=1.0 - 1e-9), TS, x0=0.3, v0=-0.2)
    d1, d2 = xp - xc, xc - xm
    assert np.max(np.abs(d1)) < 1e-8
    # symmetric first-order dependence on c (second order is 1e-18): no noise at 1e-16 level
    assert np.max(np.abs(d1 - d2)) < 1e-15


def test_release_time_closed_form():
    # g = 0: force cos(2t) turns positive at 2t = 3 pi / 2 (mod 2 pi)
    assert mp_release_time(PAPER, 2.1) == pytest.approx(3 * math.pi / 4, rel=0, abs=4e-16)
    assert mp_release_time(PAPER, 3.0) == 3.0               # cos(6) > 0: leaves at once
    assert mp_release_time(PAPER, 4.0) == pytest.approx(3 * math.pi / 4 + math.pi, abs=1e-15)
    p = PAPER.replace(g=0.3)
    tr = mp_release_time(p, 1.0)
    assert math.cos(2 * tr) == pytest.approx(0.3, abs=1e-15) and math.sin(2 * tr) < 0
    assert math.isinf(mp_release_time(PAPER.replace(g=1.0), 0.0))    # k g >= 1


def test_reference_finds_the_grazing_dip_with_the_analytic_speed():
    """Start on the steady orbit x_p (amplitude A, acceleration A w^2 at its minimum) with
    the wall 1e-10 A above the minimum: the impact speed is sqrt(2 A w^2 1e-10 A) to
    relative O(1e-10) + the 1e-6 relative rounding of the 1e-10 A depth."""
    x0, v0, A = steady_orbit(PAPER)
    p = PAPER.replace(g=-A * (1 - 1e-10))
    R = mp_cached(p, 1, x0, v0)
    expect = A * PAPER.omega * math.sqrt(2e-10)
    assert R.v[0] == pytest.approx(-expect, rel=1e-5)
    # the dip's minimum of x_p is at w t = pi + atan2(Q, P); the impact a hair before it
    P, Q = x0, v0 / PAPER.omega
    t_min = (math.pi + math.atan2(Q, P)) / PAPER.omega
    assert 0 < t_min - R.t[0] < 1e-4


def test_near_miss_has_no_impact_in_the_reference():
    x0, v0, A = steady_orbit(PAPER)
    R = mp_cached(PAPER.replace(g=-A * (1 + 1e-6)), 1, x0, v0, t_max=60.0)
    assert R.t.size == 0 and R.reason == "t_max"


# cases without chatter, sticking or shallow dips, where solve_ivp applies
IVP_CASES = ["paper", "c=2", "critical", "crit+1e-9", "crit-1e-9", "resonance", "res-contact",
             "r=1,c=0", "omega=20", "gap", "preload 0.3", "preload 0.5", "near miss"]


@pytest.mark.parametrize("case", [CASE_BY_NAME[n] for n in IVP_CASES], ids=IVP_CASES)
def test_mp_and_solve_ivp_references_agree(case):
    """Cross-check of the two references.  DOP853 at rtol 1e-12 carries a global error of
    ~1e-12 per unit time scale; over these <= 40 time units and <= 12 impacts we measured
    <= 2e-10, so 1e-9 (absolute in t; relative to the largest impact speed in v) is a
    tolerance for that integrator, not for the exact method."""
    R, I = reference(case), ivp_reference(case)
    assert not isinstance(I, str), I
    pairs, missed, extra, _ = match_impacts(R.t, R.v, I.t, I.v)
    assert missed == 0 and extra == 0
    if pairs:
        i, j = np.array(pairs).T
        V = np.max(np.abs(R.v))
        assert np.max(np.abs(I.t[j] - R.t[i])) < 1e-9
        assert np.max(np.abs(I.v[j] - R.v[i])) < 1e-9 * V


def test_solve_ivp_reference_refuses_chatter_and_sticking():
    with pytest.raises(ReferenceNotApplicable, match="chatter"):
        ivp_impacts(PAPER.replace(omega=0.2), 1000, t_max=25.0)
    with pytest.raises(ReferenceNotApplicable, match="sticks"):
        ivp_impacts(PAPER.replace(r=0.0), 10)


def test_chatter_reference_is_well_conditioned():
    """The physics of a chatter is well conditioned: moving the start by 1e-14 moves the
    mpmath accumulation time by O(1e-14), not more."""
    p = PAPER.replace(c=5.0)
    a = mp_cached(p, 10_000, t_max=2.3)
    b = mp_cached(p, 10_000, v0=1e-14, t_max=2.3)
    assert abs(a.sticking[0][0] - b.sticking[0][0]) < 1e-13
