"""State logic without a browser: URL parsing, validation, round trips."""
import math

import pytest
from hypothesis import given, settings as hsettings, strategies as st

from app import state


def test_defaults_are_the_papers():
    run = state.validate(state.defaults())
    p = run.params
    assert (p.m, p.c, p.k, p.g, p.r, p.omega) == (1.0, 0.05, 1.0, 0.0, 0.8, 2.0)
    assert (run.t_end, run.t_record, run.method) == (500.0, 250.0, "exact")


def test_query_restores_every_field():
    args = {"omega": "2.8", "r": "0.6", "c": "0.1", "g": "-0.25", "m": "2", "k": "3",
            "psi": repr(math.pi / (4 * 2.8)), "t_end": "300", "t_record": "100",
            "x0": "0.5", "v0": "-1", "method": "rk45", "rtol": "1e-8", "atol": "1e-10",
            "dt": "0.002", "bif_min": "0.5", "bif_max": "4", "bif_n": "120"}
    values, errors = state.parse_query(args)
    assert errors == []
    run = state.validate(values)
    assert run.params.omega == 2.8 and run.params.r == 0.6 and run.params.g == -0.25
    assert run.psi_frac == pytest.approx(1 / 8, rel=1e-12)   # pi/(4 omega) = T/8
    assert run.psi == pytest.approx(math.pi / (4 * 2.8), rel=1e-12)
    assert (run.x0, run.v0, run.method, run.rtol, run.bif_n) == (0.5, -1.0, "rk45", 1e-8, 120)


def test_bytes_and_lists_as_tornado_gives_them():
    values, errors = state.parse_query({"omega": [b"1.2"], "method": [b"rk4"]})
    assert errors == [] and values["omega"] == 1.2 and values["method"] == "rk4"


@pytest.mark.parametrize("name,text", [
    ("omega", "abc"), ("omega", "nan"), ("r", "inf"), ("c", "-inf"), ("m", ""),
    ("k", "1e999"), ("method", "euler"), ("bif_n", "12.5"), ("psi", "<script>"),
])
def test_garbage_is_reported_by_name_and_replaced_by_default(name, text):
    values, errors = state.initial_settings({name: text})
    assert len(errors) == 1 and errors[0].startswith(name)
    assert values[name] == state.defaults()[name]
    assert "<script>" not in errors[0]           # escaped before it reaches the page


@pytest.mark.parametrize("args,field", [
    ({"m": "-1"}, "m"), ({"m": "0"}, "m"), ({"k": "-2"}, "k"), ({"c": "-0.1"}, "c"),
    ({"r": "1.5"}, "r"), ({"r": "-0.1"}, "r"), ({"omega": "0"}, "omega"),
    ({"omega": "1e9"}, "omega"), ({"t_end": "1e12"}, "t_end"),
    ({"t_record": "600"}, "t_record"), ({"psi": "99"}, "psi"),
    ({"dt": "0"}, "dt"), ({"bif_n": "1"}, "bif_n"), ({"x0": "-1", "g": "0"}, "x0"),
])
def test_physically_invalid_link_falls_back_to_defaults(args, field):
    values, errors = state.initial_settings(args)
    assert errors and field in " ".join(errors)
    state.validate(values)                       # what is used is valid


def test_validate_names_every_bad_field_at_once():
    values = {**state.defaults(), "m": -1.0, "r": 2.0, "t_end": math.nan, "method": "x"}
    with pytest.raises(ValueError) as exc:
        state.validate(values)
    text = str(exc.value)
    for field in ("m: -1", "r: 2", "t_end", "method"):
        assert field in text


def test_empty_x0_means_at_the_wall():
    values, errors = state.parse_query({"x0": ""})
    assert errors == [] and state.validate(values).x0 is None


@hsettings(max_examples=60, deadline=None)
@given(omega=st.floats(0.01, 50), r=st.floats(0, 1), c=st.floats(0, 2),
       g=st.floats(-5, 5), m=st.floats(1e-3, 1e3), k=st.floats(0, 1e3),
       psi=st.floats(0, 1), t_end=st.floats(1, 5000))
def test_url_round_trip(omega, r, c, g, m, k, psi, t_end):
    values = {**state.defaults(), "omega": omega, "r": r, "c": c, "g": g, "m": m, "k": k,
              "psi": psi, "t_end": t_end, "t_record": t_end / 2}
    run = state.validate(values)
    back, errors = state.parse_query(state.to_query(run))
    assert errors == []
    run2 = state.validate(back)
    assert run2.params == run.params and run2.t_end == run.t_end
    assert run2.psi_frac == pytest.approx(run.psi_frac, abs=1e-12)


@hsettings(max_examples=80, deadline=None)
@given(omega=st.floats(0.05, 6), r=st.floats(0, 1), c=st.floats(0, 0.5),
       g=st.floats(-1, 1), m=st.floats(1e-3, 1e3), psi=st.floats(0, 1),
       t_end=st.floats(1, 20000))
def test_written_url_is_short_and_gives_back_the_same_run(omega, r, c, g, m, psi, t_end):
    """Any value a slider or a box may send: the URL written has at most 10 significant
    digits per number and parses back to exactly the same Run (so the same data)."""
    values = {**state.defaults(), "omega": omega, "r": r, "c": c, "g": g, "m": m,
              "psi": psi, "t_end": t_end, "t_record": t_end / 2}
    run = state.validate(values)
    q = state.to_query(run)
    for name, text in q.items():
        if name != "method":
            mantissa = text.lower().split("e")[0].replace("-", "").replace(".", "")
            assert len(mantissa.lstrip("0").rstrip("0") or "0") <= 10, (name, text)
    back, errors = state.parse_query(q)
    assert errors == [] and state.validate(back) == run


def test_slider_noise_is_computed_on_the_step_grid():
    run = state.validate({**state.defaults(), "omega": 4.2299999999999995,
                          "r": 0.30000000000000004, "psi": 0.37500000000000006})
    assert (run.params.omega, run.params.r, run.psi_frac) == (4.23, 0.3, 0.375)
    assert state.to_query(run)["omega"] == "4.23"


def test_scene_in_the_link_is_the_base_and_numbers_override_it():
    values, errors = state.parse_query({"scene": "fig5", "omega": "1.25"})
    assert errors == []
    assert (values["omega"], values["t_end"], values["t_record"]) == (1.25, 3000.0, 2500.0)
    values, errors = state.parse_query({"scene": "fig99"})
    assert values == state.defaults() and errors and errors[0].startswith("scene:")
    run = state.validate(state.parse_query({"scene": "fig4"})[0])
    assert state.to_query(run, "fig4")["scene"] == "fig4"


# -- the URL is the state ---------------------------------------------------------------

from app.scenes import SCENES                                    # noqa: E402
from app.settings import BY_NAME, QUERY_NAMES, SWEEP_RANGES       # noqa: E402


def _text_for(name):
    """Texts a link may carry for ``name``: its own kind of value, in and out of range,
    and garbage."""
    s = BY_NAME[name]
    garbage = st.sampled_from(["", "nan", "inf", "-1e400", "banana", "1,5", "0x10", " 2 "])
    if s.kind == "flag":
        return st.one_of(st.sampled_from(["0", "1", "true", "off", "yes"]), garbage)
    if s.kind == "choice":
        return st.one_of(st.sampled_from(list(s.choices)), garbage)
    numbers = st.floats(-1e4, 1e4, allow_nan=False) | st.integers(-10, 3000)
    if s.soft:
        numbers = numbers | st.floats(*s.soft)
    if name in ("bif_min", "bif_max"):
        numbers = numbers | st.floats(-1.0, 5.0)
    return st.one_of(numbers.map(repr), numbers.map(lambda v: f"{v:.3g}"), garbage)


QUERIES = st.fixed_dictionaries({}, optional={
    **{n: _text_for(n) for n in QUERY_NAMES},
    "scene": st.sampled_from([sc.key for sc in SCENES] + ["fig99", ""])})


@hsettings(max_examples=300, deadline=None)
@given(q=QUERIES)
def test_any_link_shows_a_state_whose_url_reproduces_it(q):
    """Whatever the query: the page shows a valid state, and the URL written for it gives
    back that same state (settings, scene, display) and that same URL, with no error."""
    values, scene, errors = state.from_query(q)
    run = state.validate(values)                  # the state shown is always valid
    display = {n: values[n] for n in state.DISPLAY_FIELDS}
    url = state.to_query(run, scene, display)
    values2, scene2, errors2 = state.from_query(url)
    assert errors2 == [], (url, errors2)
    run2 = state.validate(values2)
    assert (run2, scene2) == (run, scene)
    assert {n: values2[n] for n in state.DISPLAY_FIELDS} == display
    assert state.to_query(run2, scene2, display) == url
    # the boxes show the numbers computed with (no empty range after a parameter switch)
    assert run.bif_min is not None and run.bif_max is not None


def test_one_bad_field_in_a_link_is_refused_alone():
    values, scene, errors = state.from_query({"omega": "2.5", "r": "5", "c": "0.1"})
    run = state.validate(values)
    assert (run.params.omega, run.params.r, run.params.c) == (2.5, 0.8, 0.1)
    assert len(errors) == 1 and errors[0].startswith("r: 5 ") and "[0, 1]" in errors[0]
    values, scene, errors = state.from_query({"scene": "fig6", "r": "-3", "omega": "2.7"})
    run = state.validate(values)
    assert (scene, run.params.r, run.params.omega) == ("fig6", 0.8, 2.7)


def test_a_link_choosing_the_diagram_parameter_gets_its_range():
    run = state.validate(state.from_query({"bif_param": "r"})[0])
    assert (run.bif_min, run.bif_max) == SWEEP_RANGES["r"]


def test_a_scene_link_carries_only_what_differs_from_the_scene():
    run = state.validate({**state.base_settings("fig6"), "r": 0.6})
    assert state.to_query(run, "fig6") == {"scene": "fig6", "r": "0.6"}
    assert state.to_query(state.base_run("fig2"), "fig2") == {"scene": "fig2"}
