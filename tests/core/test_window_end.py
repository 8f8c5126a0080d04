"""Where a run ends is no event: the final state is continuous in t_end, and a periodic
orbit's n-period map returns to the orbit from every section phase.

References are exact identities of the motion: x(t) is continuous, (x, v) is
continuous in flight with |x(t + d) - x(t) - v d| <= A d^2 / 2 and |v(t + d) - v(t)| <=
A d (A bounding |a| = |cos(omega t) - c v - k x| / m near t), a run ended at an impact
instant stops in one of the two one-sided states (g, v-) or (g, -r v-), and a periodic
orbit is a fixed point of the n-period map from every phase (its multipliers, the
eigenvalues of a conjugate map, do not depend on the phase).
"""
import math

import numpy as np
import pytest

import impactlib as il

from core_helpers import PAPER

D = 1e-9          # the offset of t_end
ROUND = 1e-10     # rounding of a run of a few periods (impact times to ~1e-15 relative,
                  # moved by saltation matrices of size <= 1e3 over <= 30 impacts)


def random_cases(seed, n):
    """Parameters over every damping regime (Eq. (1) damps with 2 c x', so c = sqrt(k m)
    is critical) and starts."""
    rng = np.random.default_rng(seed)
    cases = []
    for i in range(n):
        k = float(rng.uniform(0.5, 2.0))
        c = [0.0, float(rng.uniform(0.01, 0.5)), math.sqrt(k), float(rng.uniform(1.5, 3.0))][i % 4]
        p = il.Params(m=1.0, c=c, k=k, g=float(rng.uniform(-0.5, 1.0)),
                      r=float(rng.uniform(0.3, 0.95)), omega=float(rng.uniform(0.7, 4.0)))
        x0 = p.g + float(rng.uniform(0.0, 2.0))
        cases.append((p, x0, float(rng.uniform(-2.0, 2.0)), float(rng.uniform(0.0, 10.0))))
    return cases


ISSUE = (il.Params(m=1.0, c=0.0, k=1.0, g=0.9, r=0.8, omega=2.8),
         2.4696835891088798, 0.2352569478608384, 3.1473362591860408)
CASES = [ISSUE] + random_cases(18, 24)


def run(p, t_end, x0, v0, t0):
    sol = il.simulate(p, t_end=t_end, x0=x0, v0=v0, t0=t0, t_record=t0)
    assert sol.status == 0, sol.message
    return sol


def accel_bound(p, x, v):
    return (1.0 + p.c * (abs(v) + 1.0) + p.k * (abs(x) + 1.0)) / p.m


def events_near(sol, te, w):
    """True if an impact, a sticking or a release lies within w of te."""
    ts = list(sol.impacts.t) + [t for iv in sol.sticking for t in iv]
    return any(abs(t - te) <= w for t in ts)


def assert_continuous(p, a, b, d):
    """b ends d after a, both in flight or both at rest, no event between."""
    ta, xa, va, sa = a.final
    tb, xb, vb, sb = b.final
    assert sa == sb, (a.final, b.final)
    assert len(a.impacts) == len(b.impacts), (a.impacts.t, b.impacts.t)
    A = accel_bound(p, xa, va)
    scale = 1.0 + abs(xa) + abs(va)
    assert abs(xb - xa - va * d) <= A * d * d + ROUND * scale, (a.final, b.final)
    assert abs(vb - va) <= A * abs(d) + ROUND * scale, (a.final, b.final)


def ends_of(p, x0, v0, t0):
    """Multiples of T (and T / 2) from t0, random ends, and the first impact instants."""
    ref = run(p, t0 + 6.0 * p.T, x0, v0, t0)
    ends = [t0 + k * p.T for k in (1, 2, 3, 5)] + [t0 + 0.5 * p.T, t0 + 2.5 * p.T]
    ends += list(t0 + np.random.default_rng(7).uniform(0.0, 6.0 * p.T, 3))
    return ref, ends, [t for t in ref.impacts.t[:6] if t > t0]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_final_state_is_continuous_in_t_end(case):
    p, x0, v0, t0 = CASES[case]
    ref, ends, impact_ends = ends_of(p, x0, v0, t0)
    checked = 0
    for te in ends:
        if events_near(ref, te, 10 * D):
            continue
        mid = run(p, te, x0, v0, t0)
        assert_continuous(p, run(p, te - D, x0, v0, t0), mid, D)
        assert_continuous(p, mid, run(p, te + D, x0, v0, t0), D)
        checked += 1
    assert checked >= 6
    for te in impact_ends:
        before, at, after = (run(p, te + d, x0, v0, t0) for d in (-D, 0.0, D))
        tb, xb, vb, sb = before.final
        ta, xa, va, sa = at.final
        assert not sb and vb < 0.0 and abs(xb - p.g) <= -vb * D + ROUND
        # at the instant: the state just before or just after the impact, nothing else
        assert abs(xa - p.g) <= ROUND * (1.0 + abs(p.g)), at.final
        scale = ROUND * (1.0 + abs(vb))
        before_side = abs(va - vb) <= accel_bound(p, xb, vb) * D + scale and not sa
        after_side = (abs(va - after.final[2]) <= accel_bound(p, xb, vb) * D + scale
                      and sa == after.final[3])
        assert before_side or after_side, (before.final, at.final, after.final)


def test_issue_example_has_one_impact_and_ends_in_flight_at_every_kT():
    p, x0, v0, t0 = ISSUE
    for k in (1, 2, 3, 4):
        for d in (-D, 0.0, D):
            sol = run(p, t0 + k * p.T + d, x0, v0, t0)
            t, x, v, stuck = sol.final
            assert not stuck and x > p.g + 1.0 and np.all(sol.impacts.v < -1.0), sol.final
            assert len(sol.impacts) == k
    # t0 + T / 2 is this orbit's impact instant: one impact, no sticking
    for d in (-D, 0.0, D):
        sol = run(p, t0 + 0.5 * p.T + d, x0, v0, t0)
        assert not sol.final[3] and len(sol.sticking) == 0 and np.all(sol.impacts.v < -1.0)


# ---------------------------------------------------------------- periodic orbits

ORBITS = {
    # name: (params, n, (x0, v0, t0) or None for the settled attractor, stable expected)
    "issue, undamped, stable": (ISSUE[0], 1, ISSUE[1:], True),
    "paper default, stable": (PAPER, 1, None, True),
    "paper at 2.8, unstable": (PAPER.replace(omega=2.8), 1, None, False),
    "paper at 1.2, period 2": (PAPER.replace(omega=1.2), 2, None, True),
    "critical damping": (il.Params(m=1.0, c=1.0, k=1.0, g=-0.4, r=0.8, omega=0.5), 1, None, True),
    "critical damping, sticks": (il.Params(m=1.0, c=1.0, k=1.0, g=0.05, r=0.8, omega=1.0), 1,
                                 None, True),
    "overdamped": (il.Params(m=1.0, c=3.0, k=1.0, g=-0.3, r=0.8, omega=0.5), 1, None, True),
    "overdamped, sticks": (il.Params(m=1.0, c=3.0, k=1.0, g=0.02, r=0.8, omega=1.0), 1, None,
                           True),
    "preload k g = 0.97, sticks": (il.Params(m=1.0, c=0.05, k=1.0, g=0.97, r=0.8, omega=2.0),
                                    1, None, True),
    "preload k g = 0.9, r = 0.5": (il.Params(m=1.0, c=0.1, k=2.0, g=0.45, r=0.5, omega=1.5),
                                   1, None, True),
}


def canonical(p, x, v):
    """A state on the wall moving in is the same point of the map as its rebound."""
    if abs(x - p.g) <= ROUND * (1.0 + abs(p.g)) and v < 0.0:
        return np.array([p.g, -p.r * v])
    return np.array([x, v])


def state_at(p, orb, t):
    """The orbit's state at time t >= orb.phase (a run from the orbit's section)."""
    if t == orb.phase:
        return orb.x, orb.v
    sol = il.simulate(p, t_end=t, t_record=t, x0=orb.x, v0=orb.v, t0=orb.phase)
    # a state on the wall may come back a rounding behind it
    return max(sol.final[1], p.g), sol.final[2]


@pytest.fixture(scope="module", params=list(ORBITS))
def orbit(request):
    p, n, start, stable = ORBITS[request.param]
    x0, v0, t0 = start if start is not None else (None, None, 0.0)
    orb = il.periodic_orbit(p, n, x0=x0, v0=v0, phase=t0 % p.T)
    assert orb.converged and orb.stable == stable, orb
    if start is not None:
        # started on an exact orbit: Newton stays there
        assert (orb.x, orb.v) == pytest.approx((x0, v0), abs=1e-10) and not orb.sticks
    return p, n, orb


def section_phases(p, orb):
    phases = list(np.linspace(0.0, p.T, 16, endpoint=False))
    return phases + [float(t % p.T) for t in orb.impact_times]


def test_n_period_map_returns_to_the_orbit_from_every_phase(orbit):
    p, n, orb = orbit
    phases = section_phases(p, orb)
    assert len(phases) >= 16 + (0 if orb.sticks else len(orb.impact_times))
    for ph in phases:
        t = orb.phase + (ph - orb.phase) % p.T
        x, v = state_at(p, orb, t)
        sol = il.simulate(p, t_end=t + n * p.T, t_record=t, x0=x, v0=v, t0=t)
        assert sol.status == 0
        z, z1 = canonical(p, x, v), canonical(p, sol.final[1], sol.final[2])
        # an unstable orbit amplifies the rounding of the start by |multiplier|
        tol = 1e-9 * (1.0 + np.max(np.abs(z))) * max(1.0, abs(orb.multipliers[0]))
        assert np.max(np.abs(z1 - z)) <= tol, (ph, z, z1, sol.final)


def test_orbit_found_again_from_every_phase_with_the_same_multipliers(orbit):
    p, n, orb = orbit
    for ph in list(np.linspace(0.0, p.T, 16, endpoint=False)) + [orb.phase]:
        t = orb.phase + (ph - orb.phase) % p.T
        x, v = state_at(p, orb, t)
        again = il.periodic_orbit(p, n, x0=max(x, p.g), v0=v, phase=float(t % p.T))
        assert again.converged and again.sticks == orb.sticks, (ph, again)
        z = canonical(p, x, v)
        assert np.max(np.abs(canonical(p, again.x, again.v) - z)) <= 1e-8 * (1.0 + np.max(np.abs(z)))
        assert again.impacts == orb.impacts
        # conjugate maps: the same multipliers (to the rounding of the Jacobians)
        np.testing.assert_allclose(np.abs(again.multipliers), np.abs(orb.multipliers),
                                   rtol=1e-6, atol=1e-9)
