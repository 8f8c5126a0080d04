"""Bad inputs: each raises one ValueError that names the field and its value."""
import math

import numpy as np
import pytest

import impactlib as il
from impactlib.model import rk4_stability_limit

from core_helpers import PAPER


@pytest.mark.parametrize("field, value, words", [
    ("m", math.nan, "m=nan"), ("c", math.inf, "c=inf"), ("k", -math.inf, "k=-inf"),
    ("g", "abc", "g='abc'"), ("r", None, "r=None"), ("omega", True, "omega=True"),
    ("m", 0.0, "m=0.0 must be > 0"), ("m", -1.0, "m=-1.0 must be > 0"),
    ("k", -1e-3, "k=-0.001 must be >= 0"), ("c", -0.1, "c=-0.1 must be >= 0"),
    ("r", -0.01, "r=-0.01 must lie in [0, 1]"), ("r", 1.5, "r=1.5 must lie in [0, 1]"),
    ("omega", 0.0, "omega=0.0 must be > 0"), ("omega", -2.0, "omega=-2.0 must be > 0"),
])
def test_bad_parameter_names_the_field(field, value, words):
    with pytest.raises(ValueError) as info:
        PAPER.replace(**{field: value})
    assert words in str(info.value)


def test_every_bad_field_in_one_message():
    with pytest.raises(ValueError) as info:
        il.Params(m=-1.0, c=-1.0, k=math.nan, r=2.0, omega=0.0)
    msg = str(info.value)
    for words in ("m=-1.0", "c=-1.0", "k=nan", "r=2.0", "omega=0.0"):
        assert words in msg


def test_unknown_parameter_name():
    with pytest.raises(ValueError, match="unknown parameter name.*'mass'"):
        PAPER.replace(mass=2.0)
    with pytest.raises(ValueError, match="'zeta' is unknown"):
        il.bifurcation(PAPER, "zeta", [1.0, 2.0], t_end=10.0, t_record=0.0)
    with pytest.raises(ValueError, match="'q' is unknown"):
        il.regime_map(PAPER, "omega", [1.0], "q", [0.5], t_end=10.0, t_record=0.0)


@pytest.mark.parametrize("kwargs, words", [
    (dict(x0=-0.1), "x0=-0.1 is behind the endstop g=0.0"),
    (dict(t_record=-1.0), "t_record=-1.0 must lie in [0, t_end=500.0]"),
    (dict(t_record=600.0), "t_record=600.0 must lie in [0, t_end=500.0]"),
    (dict(t_end=math.nan), "t_end=nan is not finite"),
    (dict(v0=math.inf), "v0=inf is not finite"),
    (dict(x0="zero"), "x0='zero' is not a number"),
    (dict(method="euler"), "method='euler' is unknown"),
    (dict(method="rk4"), "dt is required for method='rk4'"),
    (dict(method="rk4", dt=-0.01), "dt=-0.01 must be > 0"),
    (dict(method="rk45", rtol=0.0), "rtol=0.0 must lie in [1e-14, 1)"),
])
def test_bad_run_setting_names_the_field(kwargs, words):
    with pytest.raises(ValueError) as info:
        il.simulate(PAPER, **kwargs)
    assert words in str(info.value)


def test_rk4_beyond_stability_limit_is_a_clear_error():
    p = PAPER.replace(k=1e4)                # fastest rate 100 1/s: limit 2.78 / 100
    lim = rk4_stability_limit(p)
    assert lim == pytest.approx(0.0278, rel=1e-3)
    with pytest.raises(ValueError, match=r"dt=0\.05 exceeds the RK4 stability limit 0\.0278"):
        il.simulate(p, t_end=1.0, t_record=0.0, method="rk4", dt=0.05)
    # just inside the limit runs (and stays bounded: the step is stable)
    sol = il.simulate(p, t_end=1.0, t_record=0.0, method="rk4", dt=0.99 * lim)
    assert sol.success
    assert np.all(np.abs(sol.poincare.x) < 1.0)


def test_rk4_stability_limit_is_a_real_limit():
    """The limit protects against a real blow-up: one step beyond it, RK4's amplification
    of the free oscillation exceeds 1 (|R(i h w)| > 1 for h w > 2.83)."""
    w = 100.0
    for hw, grows in [(2.7, False), (2.9, True)]:
        z = 1j * hw
        R = 1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24
        assert (abs(R) > 1) == grows
    assert rk4_stability_limit(PAPER.replace(k=w * w)) * w <= 2.83


def test_bad_sweep_values():
    with pytest.raises(ValueError, match="non-finite"):
        il.bifurcation(PAPER, "omega", [1.0, math.nan], t_end=10.0, t_record=0.0)
    with pytest.raises(ValueError, match="omega=-1.0 must be > 0"):
        il.bifurcation(PAPER, "omega", [1.0, -1.0], t_end=10.0, t_record=0.0)
    with pytest.raises(ValueError, match="r=1.5 must lie in"):
        il.bifurcation(PAPER, "r", [0.5, 1.5], t_end=10.0, t_record=0.0)


def test_t_record_defaults_to_half_of_t_end():
    """The paper's window (250 of 500) is the default, and a shorter run keeps its second
    half instead of failing on a t_record beyond t_end."""
    assert il.simulate(PAPER).t_record == 250.0
    short = il.simulate(PAPER, t_end=100.0)
    assert short.t_record == 50.0
    explicit = il.simulate(PAPER, t_end=100.0, t_record=50.0)
    np.testing.assert_array_equal(short.impacts.t, explicit.impacts.t)
    assert short.impacts.t.size > 0 and short.impacts.t.min() >= 50.0
    with pytest.raises(ValueError, match="t_end"):
        il.simulate(PAPER, t_end=-1.0)
