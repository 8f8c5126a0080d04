"""simulate(dense=times): samples at given times, checked against the closed-form steady
state of the linear oscillator, and refused with a message naming the field."""
import math

import numpy as np
import pytest

import impactlib as il


@pytest.mark.parametrize("method,kw,tol", [
    # closed form: rounding only (measured 1.2e-14)
    ("exact", {}, 1e-12),
    # rk4 dt = 1e-3 over 450k steps, Hermite samples between steps: measured 1.5e-10;
    # 1e-9 keeps a sixfold margin and fails at dt = 0.1 (8e-6)
    ("rk4", {"dt": 1e-3}, 1e-9),
])
def test_samples_at_given_times_follow_the_steady_state(method, kw, tol):
    """No impacts (wall far away), transient decayed by e^-40 by t = 400: x(t) is
    X cos(ωt − φ) at uneven, repeated and end-point times alike."""
    m, c, k, w = 1.0, 0.1, 1.0, 1.3
    p = il.Params(m=m, c=c, k=k, g=-10.0, r=0.8, omega=w)
    rng = np.random.default_rng(18)
    times = np.sort(np.concatenate([rng.uniform(400.0, 450.0, 300), [400.0, 425.0, 425.0, 450.0]]))
    sol = il.simulate(p, t_end=450.0, t_record=400.0, dense=times, method=method, **kw)
    X = 1 / math.hypot(k - m * w * w, 2 * c * w)     # m x" + 2c x' + k x = cos(ωt)
    phi = math.atan2(2 * c * w, k - m * w * w)
    assert np.array_equal(sol.dense.t, times)
    assert np.max(np.abs(sol.dense.x - X * np.cos(w * times - phi))) <= tol
    assert np.max(np.abs(sol.dense.v + X * w * np.sin(w * times - phi))) <= tol


def test_given_times_sample_the_same_run_as_even_ones():
    """The times of dense=n given as an array: the same samples bit for bit (an exact
    identity: the sample times are not part of the run's steps)."""
    p = il.Params()
    even = il.simulate(p, dense=777)
    given = il.simulate(p, dense=np.linspace(250.0, 500.0, 777))
    for a, b in ((even.dense.x, given.dense.x), (even.dense.v, given.dense.v),
                 (even.impacts.t, given.impacts.t)):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("dense,says", [
    ([300.0, 299.0], "ascending"),
    ([[300.0]], "1-D"),
    ([300.0, math.nan], "finite"),
    ("300", "whole number"),
    (-1, "whole number"),
    ([240.0, 300.0], "must lie in the window [t_record, t_end] = [250.0, 500.0]"),
    ([300.0, 500.5], "must lie in the window"),
])
def test_bad_sample_times_are_refused_by_name(dense, says):
    with pytest.raises(ValueError) as err:
        il.simulate(il.Params(), dense=dense)
    assert "dense" in str(err.value) and says in str(err.value)
