"""The exact method against the independent mpmath reference on every case of the report.

Tolerances
----------
STANDARD = 1e-10, absolute in impact time (times here are <= 170) and relative to the
largest impact speed V in velocity.  The issue asks for 1e-9; the exact method evaluates
a closed form per flight and refines each impact to a few ulps, so over these <= 70
impacts we measure <= 1e-11 (omega = 0.01: phases of t ~ 160) and typically 1e-15.

Where a case amplifies rounding the tolerance is not loosened by hand but measured:

* grazing: the first impact's speed sqrt(2 a delta) depends on a depth delta = 1e-10 A
  known to eps A, so a 1-ulp change of the start moves it by ~1e-6 relative.  The test
  moves the reference's start by one ulp and allows 16 times that movement.
* chatter: the accumulation time where a chatter ends on the wall.  The physics is well
  conditioned (test_reference.test_chatter_reference_is_well_conditioned), but the method
  evaluates the tiny last hops as x = h + x_p, a difference of O(X) terms (X = forced
  amplitude + |g|), so a hop of speed v is timed to ~eps X / v and the summed tail starts
  from a speed known to ~a eps X / v: the accumulation time is off by ~2 eps X / ((1-r) v),
  v the last recorded impact speed (the tail is summed once its error bound is at
  rounding level, test_chatter_tail: v ~ 1e-5..1e-7).  Tolerance: 4 times that model (8 eps X / ((1-r) v)), and
  test_chatter_rounding_spread measures the spread directly.
* the preload 0.5 transient amplifies rounding about tenfold per impact after t ~ 20:
  test_preload_transient_error_tracks_the_ulp_sensitivity compares the error impact by
  impact with the reference moved by one ulp.
"""
import math

import numpy as np
import pytest

import impactlib as il
from impactlib.verify.report import CASE_BY_NAME, CASES, compare, reference, steady_orbit
from impactlib.verify.reference import ivp_impacts, mp_impacts

from core_helpers import EPS, PAPER, mp_cached

STANDARD = 1e-10


def run(case, **kw):
    return il.simulate(case.params, t_end=case.t_end, t_record=0.0, x0=case.x0, v0=case.v0,
                       dense=200 if case.dense else 0, **kw)


def ulp_sensitivity(case):
    """Largest movement of the reference's impact times and speeds when x0 moves by 1 ulp."""
    x0 = max(0.0, case.params.g) if case.x0 is None else case.x0
    R = reference(case)
    R1 = mp_cached(case.params, 1_000_000, float(np.nextafter(x0, np.inf)), case.v0,
                   t_max=case.t_end)
    assert R1.t.size == R.t.size
    return np.abs(R1.t - R.t), np.abs(R1.v - R.v)


def chatter_bound(case, sol, start):
    """Model bound 8 eps X / ((1 - r) |v_last|) on the accumulation-time error (module doc)."""
    p = case.params
    if p.r == 0:
        return 0.0                    # plastic: sticks at the impact itself, no tail
    v_last = abs(sol.impacts.v[sol.impacts.t <= start][-1])
    X = steady_orbit(p)[2] + abs(p.g)
    return 8 * EPS * X / ((1 - p.r) * v_last)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_exact_matches_the_mpmath_reference(case):
    sol = run(case)
    assert sol.success, sol.message
    R = reference(case)
    cmp = compare(case, sol)
    # zero missed and zero extra impacts, on every case (the grazing one included)
    assert cmp.missed == 0 and cmp.extra == 0
    # every reference impact faster than 1e-4 V is compared one by one
    assert cmp.compared == int(np.sum(np.abs(R.v) >= 1e-4 * cmp.v_scale))
    tol_t = tol_v = STANDARD
    if case.name == "grazing":
        st, sv = ulp_sensitivity(case)
        tol_t = max(STANDARD, 16 * st.max())
        tol_v = max(STANDARD, 16 * sv.max() / cmp.v_scale)
    if cmp.compared:
        assert cmp.err_t <= tol_t
        assert cmp.err_v <= tol_v
    if case.dense:
        # x = t sin t / 2 grows to ~50 over [0, 100]: 1e-12 of that scale
        assert R.t.size == 0 and sol.impacts.t.size == 0
        assert cmp.err_state <= 1e-12 * 50
    # every sticking interval of the reference, to the chatter model (or STANDARD)
    assert len(sol.sticking) == len(R.sticking)
    for (s_ref, rel_ref), (s, rel) in zip(R.sticking, sol.sticking):
        assert abs(s - s_ref) <= max(STANDARD, chatter_bound(case, sol, s))
        if rel_ref < case.t_end:
            assert abs(rel - rel_ref) <= 4 * EPS * rel_ref      # closed-form release time


def test_grazing_amplification_is_measured_not_assumed():
    """Show the amplification: a 1-ulp move of the start changes the grazing impact's speed
    by ~1e-6 relative in the high-precision reference itself, and the exact method's error
    is of that size (not larger)."""
    case = CASE_BY_NAME["grazing"]
    st, sv = ulp_sensitivity(case)
    R = reference(case)
    rel = sv[0] / abs(R.v[0])
    assert 1e-8 < rel < 1e-5                  # ~1e-10 amplification of a 1e-16 change
    sol = run(case)
    err = np.abs(sol.impacts.v - R.v)
    assert np.all(err <= 16 * np.maximum(sv, 1e-15))


def test_chatter_rounding_spread():
    """Chatter hops are evaluated as increments from their start on the wall (expm1 and
    half-angle forms), so the tail keeps relative accuracy: starts that differ by 1e-17 to
    6e-17 in v0 (a physical change of ~1e-16 in the accumulation time, see the reference
    test) must give accumulation times within 1e-12 of each other and of the mpmath
    reference (1e-12 = ~100 ulp at t ~ 2; before the increment form the scatter was 1e-9)."""
    case = CASE_BY_NAME["c=5"]
    starts = []
    for k in range(6):
        sol = il.simulate(case.params, t_end=2.3, t_record=0.0, v0=k * 1e-17)
        starts.append(sol.sticking[0, 0])
    ref = reference(case).sticking[0][0]
    assert max(starts) - min(starts) <= 1e-12
    assert max(abs(s - ref) for s in starts) <= 1e-12


def test_preload_transient_error_tracks_the_ulp_sensitivity():
    """preload g = 0.5 beyond the report's window: errors grow ~10x per impact, exactly as
    the reference's own response to a 1-ulp change of the start does.  The exact method
    stays within 16 times that sensitivity (floor 1e-13) impact by impact."""
    p = PAPER.replace(g=0.5)
    R = mp_cached(p, 40, None, 0.0, t_max=45.0)
    R1 = mp_cached(p, 40, float(np.nextafter(0.5, 1.0)), 0.0, t_max=45.0)
    sol = il.simulate(p, t_end=45.0, t_record=0.0)
    n = R.t.size
    assert sol.impacts.t.size == n == R1.t.size
    sens = np.abs(R1.t - R.t)
    err = np.abs(sol.impacts.t - R.t)
    assert sens[-1] > 1e3 * max(sens[5], 1e-16)      # the amplification is real
    assert np.all(err <= 16 * np.maximum(sens, 1e-13))


def test_near_critical_is_continuous_in_c():
    """c = 1 +- 1e-9 lands on the two sides of the critical formula switch; impacts must
    move by O(1e-9), smoothly, with no jump from cancellation."""
    t = {}
    for name in ("crit-1e-9", "critical", "crit+1e-9"):
        t[name] = run(CASE_BY_NAME[name]).impacts.t
    d1 = t["critical"] - t["crit-1e-9"]
    d2 = t["crit+1e-9"] - t["critical"]
    assert np.max(np.abs(d1)) < 1e-8 and np.max(np.abs(d2)) < 1e-8
    assert np.max(np.abs(d1 - d2)) < 1e-13


@pytest.mark.parametrize("c", [1e-8, 1e-10])
@pytest.mark.parametrize("r, g", [(0.5, 0.35), (0.8, 0.35), (0.8, 0.0)])
def test_lightly_damped_exact_resonance_matches_solve_ivp(c, r, g):
    """omega = omega_n with c tiny but not 0, four forcing periods from the wall, against
    DOP853 with event location (rtol 1e-12: within 2e-10 of the mpmath reference over
    runs of this length, test_reference).

    Tolerance: the closed form sums a particular and a homogeneous part of size
    FA = 1/(2 c omega) each, which cancel in x, so x carries rounding of a few eps FA
    (1.1e-6 at c = 1e-10); an impact time moves by that over |v|, a speed by that times
    omega = 1.  16 eps FA leaves room for the growth over the 8 impacts (measured <= 3.3
    eps FA), and 1e-9 for the integrator.  The step ceiling of 200 000 is far above the
    few thousand evaluations the run needs; at rounding-size steps it would end the run."""
    p = il.Params(m=0.35, c=c, k=0.35, g=g, r=r, omega=1.0)
    t_end = 4 * 2 * math.pi
    sol = il.simulate(p, t_end=t_end, t_record=0.0, x0=0.35, v0=0.0,
                      limits=il.RunLimits(max_steps=200_000))
    assert sol.status == il.RunStatus.OK, sol.message
    ref = ivp_impacts(p, 1000, x0=0.35, v0=0.0, t_max=t_end)
    assert sol.impacts.t.size == ref.t.size >= 4
    tol = 16 * EPS / (2 * c * p.omega) + 1e-9
    assert np.max(np.abs(sol.impacts.t - ref.t) * np.abs(ref.v)) < tol
    assert np.max(np.abs(sol.impacts.v - ref.v)) < tol
