"""One contract every method (exact, rk4 with a small dt, rk45 tight) must pass: the first
20 impacts of the paper's default scene against the mpmath reference, plus the shape of
a Solution."""
import math

import numpy as np
import pytest

import impactlib as il

from core_helpers import PAPER, mp_cached

N = 20

# (method kwargs, tolerance on impact time and on velocity relative to V, x >= g slack)
METHODS = {
    # closed form: ~1e-15 measured; 1e-12 leaves a thousandfold margin
    "exact": (dict(method="exact"), 1e-12, 1e-15),
    # RK4 global error ~ C dt^4: measured 1.9e-11 (t) and 6e-12 (v) at dt = 1e-3 over these
    # 65 s; 1e-9 keeps a fiftyfold margin and still fails at dt = 1e-2 (v error 5e-9)
    "rk4": (dict(method="rk4", dt=1e-3), 1e-9, 1e-9),
    # Dormand-Prince at rtol 1e-10 (atol 1e-13): error ~ 10..100 rtol after 20 impacts
    # (measured 2e-11 in t, 1.7e-10 in v); 1e-8
    "rk45": (dict(method="rk45", rtol=1e-10, atol=1e-13), 1e-8, 1e-9),
}


@pytest.fixture(scope="module")
def ref():
    return mp_cached(PAPER, N + 1)


@pytest.mark.parametrize("name", list(METHODS))
def test_every_method_meets_the_contract(name, ref):
    kw, tol, slack = METHODS[name]
    t_end = 0.5 * (ref.t[N - 1] + ref.t[N])          # between the 20th and 21st impact
    sol = il.simulate(PAPER, t_end=t_end, t_record=0.0, dense=2000, **kw)
    assert sol.success and sol.status == 0 and sol.method == name
    imp = sol.impacts
    assert len(imp) == N                              # no missed, no extra impact
    V = np.max(np.abs(ref.v[:N]))
    assert np.max(np.abs(imp.t - ref.t[:N])) <= tol
    assert np.max(np.abs(imp.v - ref.v[:N])) <= tol * V
    # shape of the result
    for arr in (imp.t, imp.phase, imp.v, sol.poincare.t, sol.poincare.x, sol.poincare.v):
        assert arr.dtype == np.float64 and arr.ndim == 1
    assert np.all(np.diff(imp.t) > 0)
    assert np.all(imp.v <= 0)
    np.testing.assert_allclose(imp.phase, np.mod(imp.t, PAPER.T), rtol=0, atol=1e-12)
    assert np.all((imp.phase >= 0) & (imp.phase < PAPER.T))
    # Poincare samples at t = n T inside the window, and the dense trajectory stays in front
    # of the wall
    np.testing.assert_allclose(sol.poincare.t / PAPER.T, np.round(sol.poincare.t / PAPER.T),
                               rtol=0, atol=1e-12)
    assert sol.poincare.t.size == math.floor(t_end / PAPER.T) + 1
    assert np.all(sol.dense.x >= PAPER.g - slack)
    assert sol.sticking.shape == (0, 2)


@pytest.mark.parametrize("name", list(METHODS))
def test_record_window_keeps_only_what_lies_inside(name):
    kw = METHODS[name][0]
    full = il.simulate(PAPER, t_end=60.0, t_record=0.0, **kw)
    part = il.simulate(PAPER, t_end=60.0, t_record=30.0, **kw)
    keep = full.impacts.t >= 30.0
    np.testing.assert_array_equal(part.impacts.t, full.impacts.t[keep])
    np.testing.assert_array_equal(part.impacts.v, full.impacts.v[keep])
    assert np.all(part.poincare.t >= 30.0)
