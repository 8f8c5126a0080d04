"""Bad inputs: each raises one ValueError that names the field and its value."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import impactlib as il
from impactlib.model import RunLimits, check_run, rk4_stability_limit

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


def test_negative_impact_limit_is_a_clear_error():
    with pytest.raises(ValueError, match=r"max_impacts=-1 must be >= 0"):
        il.simulate(PAPER, max_impacts=-1)


def _outcome(**kw):
    try:
        out = check_run(PAPER, method="exact", dt=None, rtol=1e-6, atol=1e-9, **kw)
    except ValueError as e:
        return str(e)
    return out, [type(v) for v in out]


_PI_UP = math.nextafter(math.pi, 4.0)
#: a valid exact run, and values on and beyond every bound check_run draws for each setting
_RUN = dict(t_end=500.0, t_record=250.0, x0=None, v0=0.0, phase=0.0, dense=0)
_EDGES = {
    "t_end": [1e-300, 0.0, -0.0, -1.0, 250.0, 1e9, math.inf, math.nan],
    "t_record": [None, 0.0, -0.0, -1e-300, 500.0, 500.0000000000001, math.inf, math.nan],
    "x0": [0.0, -0.0, -1e-300, 2.0, math.inf, -math.inf, math.nan],
    "v0": [-3.0, 1e300, math.inf, -math.inf, math.nan],
    "phase": [-0.0, -1e-300, math.pi, _PI_UP, math.inf, math.nan],
    "dense": [-1, 1, 2, 3, 5_000_000],
}
_CHANGE = st.one_of(
    st.sampled_from([(k, v) for k, vs in _EDGES.items() for v in vs]),
    st.tuples(st.sampled_from(["t_end", "t_record", "x0", "v0", "phase"]),
              st.floats(-10.0, 600.0)))


def _quick_and_full(changes, max_samples):
    kw = dict(_RUN, **dict(changes), limits=RunLimits(max_samples=max_samples))
    full = {k: np.float64(v) if isinstance(v, float) else v for k, v in kw.items()}
    return repr(_outcome(**kw)), repr(_outcome(**full))


# each setting on and beyond its bounds, and the sample limit (4) reached and passed: a
# window of length 0 holds 2 section times
_CASES = ([[(k, v)] for k, vs in _EDGES.items() for v in vs]
          + [[("t_record", 500.0), ("dense", d)] for d in (1, 2, 3)])


@pytest.mark.parametrize("max_samples", [5_000_000, 4])
@pytest.mark.parametrize("changes", _CASES, ids=lambda c: ",".join(f"{k}={v!r}" for k, v in c))
def test_quick_checks_of_plain_floats_agree_with_the_full_checks(changes, max_samples):
    """check_run answers an exact run given as Python floats in a few comparisons; the same
    values as numpy floats take every check: the answer (values and types, or the whole
    message) must be the same."""
    quick, full = _quick_and_full(changes, max_samples)
    assert quick == full


@settings(max_examples=300, deadline=None, derandomize=True)
@given(changes=st.lists(_CHANGE, max_size=3), max_samples=st.sampled_from([5_000_000, 100, 4]))
def test_quick_checks_agree_with_the_full_checks_for_any_settings(changes, max_samples):
    quick, full = _quick_and_full(changes, max_samples)
    assert quick == full


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
