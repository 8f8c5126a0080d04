"""Periodic orbits and their Floquet multipliers, against independent references:
fixed points solved by scipy.optimize.root on a closed-form residual written here, and
multipliers from central finite differences of the exact simulator's n-period map."""
import math

import numpy as np
import pytest
from scipy.optimize import root

import impactlib as il

from core_helpers import PAPER


def free_motion(p, t1, x1, v1, t):
    """Closed-form underdamped flight from (x1, v1) at t1 (independent of impactlib)."""
    a = p.c / p.m
    wd = math.sqrt(p.k / p.m - a * a)
    det = p.k - p.m * p.omega ** 2
    d = det ** 2 + (2 * p.c * p.omega) ** 2
    P, Q = det / d, 2 * p.c * p.omega / d
    xp = lambda t: P * math.cos(p.omega * t) + Q * math.sin(p.omega * t)  # noqa: E731
    vp = lambda t: p.omega * (Q * math.cos(p.omega * t) - P * math.sin(p.omega * t))  # noqa: E731
    A = x1 - xp(t1)
    B = (v1 - vp(t1) + a * A) / wd
    s = t - t1
    e = math.exp(-a * s)
    x = e * (A * math.cos(wd * s) + B * math.sin(wd * s)) + xp(t)
    v = e * ((-a * A + wd * B) * math.cos(wd * s) + (-a * B - wd * A) * math.sin(wd * s)) + vp(t)
    return x, v


def one_impact_orbit(p, guess):
    """(t1, u): impact time and velocity of a 1-impact period-1 orbit, by scipy root on
    the closed-form residual: the flight from (g, -r u) at t1 is back at (g, u) at t1 + T."""
    def residual(z):
        t1, u = z
        x, v = free_motion(p, t1, p.g, -p.r * u, t1 + p.T)
        return [x - p.g, v - u]
    res = root(residual, guess, method="hybr", options={"xtol": 1e-13})
    assert max(map(abs, residual(res.x))) < 1e-12
    return res.x


def fd_jacobian(p, z, n, h=1e-6):
    """Central differences of the exact simulator's n-period map at z."""
    def f(x, v):
        sol = il.simulate(p, t_end=n * p.T, t_record=n * p.T, x0=x, v0=v)
        assert not sol.final[3]
        return np.array(sol.final[1:3])
    J = np.empty((2, 2))
    for j in range(2):
        dz = np.zeros(2)
        dz[j] = h
        J[:, j] = (f(*(z + dz)) - f(*(z - dz))) / (2 * h)
    return J


def det_identity(p, m, n):
    return p.r ** (2 * m) * math.exp(-2 * p.c * n * p.T / p.m)


@pytest.mark.parametrize("omega", [2.0, 2.8])
def test_one_impact_orbit_matches_closed_form_root_and_fd_multipliers(omega):
    p = PAPER.replace(omega=omega)
    orb = il.periodic_orbit(p, 1, x0=None, v0=None)
    assert orb.converged and orb.impacts == 1 and orb.label == "1-impact period-1"
    # scipy starts near the orbit Newton found; it solves the closed form on its own
    t1, u = one_impact_orbit(p, (orb.impact_times[0] + 0.01, orb.impact_velocities[0] - 0.01))
    # the state on the section t = T (= 0 mod T) from the closed-form orbit
    t_sec = p.T * math.ceil(t1 / p.T)
    x, v = free_motion(p, t1, p.g, -p.r * u, t_sec)
    assert orb.x == pytest.approx(x, abs=1e-9) and orb.v == pytest.approx(v, abs=1e-9)
    J = fd_jacobian(p, np.array([x, v]), 1)
    mu_fd = np.linalg.eigvals(J)
    mu_fd = mu_fd[np.argsort(-np.abs(mu_fd))]
    np.testing.assert_allclose(orb.multipliers, mu_fd, atol=1e-6)
    assert np.linalg.det(orb.jacobian) == pytest.approx(det_identity(p, 1, 1), rel=1e-10)
    assert abs(np.prod(orb.multipliers)) == pytest.approx(det_identity(p, 1, 1), rel=1e-10)


def test_paper_default_orbit_is_stable_with_real_multipliers_near_069_068():
    orb = il.periodic_orbit(PAPER)
    assert orb.converged and orb.stable and orb.admissible
    assert np.all(orb.multipliers.imag == 0)
    assert orb.multipliers.real == pytest.approx([0.69, 0.68], abs=0.01)


def test_unstable_orbit_found_at_omega_28():
    """ω = 2.8 is chaotic (Fig. 6); the 1-impact period-1 orbit is still there, unstable."""
    orb = il.periodic_orbit(PAPER.replace(omega=2.8))
    assert orb.converged and not orb.stable and abs(orb.multipliers[0]) > 1


def test_three_impact_period_two_multipliers_by_fd_and_det_identity():
    p = PAPER.replace(omega=1.2)
    orb = il.periodic_orbit(p, n=2)
    assert orb.converged and orb.impacts == 3 and orb.label == "3-impact period-2"
    mu_fd = np.linalg.eigvals(fd_jacobian(p, np.array([orb.x, orb.v]), 2))
    mu_fd = mu_fd[np.argsort(-np.abs(mu_fd))]
    np.testing.assert_allclose(orb.multipliers, mu_fd, atol=1e-6)
    assert np.linalg.det(orb.jacobian) == pytest.approx(det_identity(p, 3, 2), rel=1e-10)


def test_sticking_orbit_has_zero_multipliers_and_says_so():
    orb = il.periodic_orbit(PAPER.replace(omega=0.2))
    assert orb.converged and orb.sticks
    np.testing.assert_array_equal(orb.multipliers, [0, 0])
    assert "sticks" in orb.message and orb.label.startswith("complete chattering")
    # the map really is locally constant: perturbed starts land on the same point
    a = il.simulate(orb.params, t_end=orb.params.T, t_record=orb.params.T, x0=orb.x + 1e-3, v0=orb.v)
    assert a.final[1:3] == pytest.approx((orb.x, orb.v), abs=1e-12)


def test_non_convergence_is_a_result():
    # a start far away with one Newton budget: reported, never raised
    orb = il.periodic_orbit(PAPER.replace(omega=2.8), n=3, x0=50.0, v0=-40.0)
    assert isinstance(orb.converged, bool)
    if not orb.converged:
        assert orb.message and math.isfinite(orb.residual)


@pytest.mark.parametrize("kwargs, field", [
    (dict(n=0), "n="), (dict(n=1.5), "n="), (dict(x0=math.nan, v0=0.0), "x0="),
    (dict(x0=0.1, v0=math.inf), "v0="), (dict(x0=-1.0, v0=0.0), "x0="), (dict(phase=-1.0), "phase=")])
def test_bad_orbit_input_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        il.periodic_orbit(PAPER, **kwargs)


def test_contract_names_and_signatures():
    """The names and call signatures issue 8 calls a contract."""
    import inspect
    sig = lambda f: [(q.name, q.default) for q in inspect.signature(f).parameters.values()]  # noqa: E731
    e = inspect.Parameter.empty
    assert sig(il.periodic_orbit) == [("p", e), ("n", 1), ("x0", None), ("v0", None), ("phase", 0.0)]
    assert sig(il.lyapunov)[:5] == [("p", e), ("t_end", 5000.0), ("t_record", 500.0), ("x0", None),
                                    ("v0", 0.0)]
    assert sig(il.continuation) == [("p", e), ("name", e), ("stop", e), ("n", 1), ("x0", None),
                                    ("v0", None), ("phase", 0.0), ("ds", None), ("max_points", 2000)]
    assert inspect.signature(il.bifurcation).parameters["lyapunov"].default is False
    orb = il.periodic_orbit(PAPER)
    for a in ("x", "v", "n", "impacts", "label", "multipliers", "stable", "admissible",
              "converged", "residual"):
        assert hasattr(orb, a)
    assert orb.multipliers.dtype == complex and orb.multipliers.shape == (2,)
    ly = il.lyapunov(PAPER, t_end=300.0, t_record=100.0)
    assert ly.exponents.shape == ly.error.shape == (2,) and ly.n_impacts > 0
    br = il.continuation(PAPER, "omega", 2.2)
    k = br.param.shape[0]
    assert br.x.shape == br.v.shape == br.stable.shape == br.admissible.shape == (k,)
    assert br.multipliers.shape == (k, 2) and br.multipliers.dtype == complex
    assert isinstance(br.events, list)


def test_multipliers_of_a_2x2_match_lapack_and_keep_their_order():
    """The closed-form 2 x 2 eigenvalues against LAPACK's (np.linalg.eigvals) on random
    matrices: real pairs, complex pairs, a defective one, a near-singular one; largest
    modulus first. Tolerance: a few ulps of the matrix norm, and sqrt(eps) of it where
    the pair is nearly repeated (eigenvalues of a 2 x 2 move as the square root of a
    perturbation there, for LAPACK as for the formula)."""
    from impactlib.analysis.orbits import multipliers_of

    rng = np.random.default_rng(20261125)
    mats = [rng.normal(size=(2, 2)) * 10.0 ** rng.uniform(-3, 1) for _ in range(400)]
    mats += [np.array([[0.7, 1.0], [0.0, 0.7]]), np.array([[0.6902, 0.0], [0.0, 0.6773]]),
             np.array([[1e-9, 2.0], [3.0, 1e-9]]), np.array([[0.0, -1.0], [1.0, 0.0]]),
             np.array([[2.0, 4.0], [1.0, 2.0 + 1e-14]])]
    # a strongly unstable orbit's Jacobian: squares beyond the float range
    mats += [rng.normal(size=(2, 2)) * 10.0 ** rng.uniform(150, 300) for _ in range(20)]
    for J in mats:
        got = multipliers_of(J)
        ref = np.linalg.eigvals(J).astype(complex)
        ref = ref[np.argsort(-np.abs(ref), kind="stable")]
        norm = np.abs(J).max()
        gap = abs(ref[0] - ref[1])
        tol = 8 * np.finfo(float).eps * norm * (1 + norm / max(gap, 1e-300)) \
            if gap > 1e-6 * norm else 4 * math.sqrt(np.finfo(float).eps) * norm
        assert abs(got[0]) >= abs(got[1])
        # as sets (a conjugate pair's order is LAPACK's: positive imaginary part first)
        assert min(abs(got[0] - ref[0]) + abs(got[1] - ref[1]),
                   abs(got[0] - ref[1]) + abs(got[1] - ref[0])) <= 2 * tol, (J, got, ref)
        if norm < 1e150:
            assert abs(got[0] * got[1] - np.linalg.det(J)) <= 16 * np.finfo(float).eps * norm ** 2 + tol * norm
