"""The diagram in any parameter and its sweep modes, without a browser.

References are single ``il.simulate`` runs: an independent start at each spot value,
and for a continuation the chain rebuilt by hand (each run started from the previous
run's final state at the forcing phase it ended with).
"""
import math

import numpy as np
import pytest
from bokeh.events import Tap

import impactlib as il
from app import diagram, state
from app.views.bifurcation import tap_value


def rows_at(view_source_parts, value, direction=0):
    cols = {c: np.concatenate([p[c] for p in view_source_parts]) for c in ("omega", "v", "t",
                                                                            "direction")}
    k = (np.abs(cols["omega"] - value) < 1e-12) & (cols["direction"] == direction)
    order = np.argsort(cols["t"][k])
    return cols["v"][k][order]


def single_run(p, **kw):
    sol = il.simulate(p, t_end=500.0, t_record=250.0, **kw)
    return np.asarray(sol.impacts.v)[:diagram.MAX_IMPACTS_PER_VALUE], sol


#: The app tests' small default range is in omega: other parameters take their own.
OWN_RANGE = {"bif_min": "", "bif_max": ""}


def test_diagram_in_r_agrees_with_single_runs(make_explorer):
    e = make_explorer(bif_param="r", bif_n="9", omega="2", **OWN_RANGE)
    run = e.bifurcation.run
    assert (run.bif_param, run.bif_min, run.bif_max) == ("r", 0.0, 1.0)
    assert e.diagram_status.object.startswith("complete: 9 r values")
    assert "in r" in e.bifurcation.figure.title.text and "ω = 2" in e.bifurcation.figure.title.text
    assert e.bifurcation.figure.xaxis.axis_label.startswith("restitution r")
    assert e.bifurcation.marker.location == 0.8
    assert set(e.bifurcation.current.data["omega"]) == {0.8}
    assert len(e.bifurcation.source.data["omega"]) > 0
    assert set(np.round(e.bifurcation.source.data["omega"], 12)) <= set(np.linspace(0, 1, 9))
    for r in (0.25, 0.625, 1.0):
        ref, _ = single_run(run.params.replace(r=r))
        got = rows_at(e.bifurcation.parts, r)
        assert got.size == ref.size > 0, r
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * max(1, np.abs(ref).max()))


def test_diagram_in_g_agrees_with_single_runs(make_explorer):
    """Sweeping g, each run starts at rest on its own wall, max(0, g)."""
    e = make_explorer(bif_param="g", bif_min="-0.1", bif_max="0.1", bif_n="5", omega="2.5")
    p = e.bifurcation.run.params
    for g in (-0.1, 0.05):
        ref, _ = single_run(p.replace(g=g), x0=max(0.0, g))
        got = rows_at(e.bifurcation.parts, g)
        assert got.size == ref.size > 0, g
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)


def test_swept_parameter_moves_the_marker_and_omega_restarts(make_explorer):
    e = make_explorer(bif_param="r", bif_n="9", **OWN_RANGE)
    gen, data = e.diagram.job.generation, e.bifurcation.source.data["omega"]
    e.settings.r = 0.6
    assert e.diagram.job.generation == gen and e.bifurcation.source.data["omega"] is data
    assert e.bifurcation.marker.location == 0.6
    e.settings.omega = 2.5
    assert e.diagram.job.generation == gen + 1
    assert e.diagram.job.done.wait(60)
    assert "ω = 2.5" in e.bifurcation.figure.title.text


def test_switching_the_parameter_takes_its_range(make_explorer):
    e = make_explorer()
    e.settings.bif_param = "c"
    assert e.diagram.job.done.wait(60)
    assert (e.settings.bif_min, e.settings.bif_max) == (0.0, 0.5)     # the boxes show it
    run = e.bifurcation.run
    assert (run.bif_param, run.bif_min, run.bif_max) == ("c", 0.0, 0.5)
    assert (e.bifurcation.figure.x_range.start, e.bifurcation.figure.x_range.end) == (0.0, 0.5)
    assert e.bifurcation.marker.location == 0.05
    assert e.message == ""


def test_cache_key_holds_parameter_and_mode():
    base = state.validate(state.defaults())
    keys = {state.validate({**state.defaults(), **kw}).diagram_key() for kw in (
        {}, {"bif_sweep": "up"}, {"bif_sweep": "both"},
        {"bif_param": "r", "bif_min": 0.1, "bif_max": 5.0 / 5})}
    assert len(keys) == 4
    # the swept value itself is not in the key; the others are
    assert base.diagram_key() == state.validate({**state.defaults(), "omega": 3.0}).diagram_key()
    r_sweep = {**state.defaults(), "bif_param": "r", "bif_min": None, "bif_max": None}
    assert (state.validate(r_sweep).diagram_key()
            == state.validate({**r_sweep, "r": 0.3}).diagram_key())
    assert (state.validate(r_sweep).diagram_key()
            != state.validate({**r_sweep, "omega": 3.0}).diagram_key())


def _chain(p, name, values, x0=0.0, v0=0.0):
    """The continuation rebuilt from single runs: run i starts from run i-1's final state
    at the time t0 in [0, T_i) where the forcing has the phase run i-1 ended with."""
    out, t0, x, v, prev = [], 0.0, x0, v0, None
    for val in values:
        q = p.replace(**{name: val})
        if prev is not None:
            (tf, xf, vf, _), om_prev = prev
            ph = math.fmod(om_prev * tf, 2 * math.pi)
            t0, x, v = ph / q.omega, xf, vf
        sol = il.simulate(q, t_end=t0 + 500.0, t_record=t0 + 250.0, x0=x, v0=v, t0=t0)
        out.append(np.asarray(sol.impacts.v)[:diagram.MAX_IMPACTS_PER_VALUE])
        prev = (sol.final, q.omega)
    return out


def test_sweep_both_gives_up_and_down_rows_as_continuations(make_explorer):
    """Up and down chains against the chain rebuilt from single runs (a window with
    stable periodic motion only, where rounding differences between the two paths die
    out instead of growing as in chaos)."""
    e = make_explorer(bif_sweep="both", bif_min="2.5", bif_max="2.65", bif_n="7", r="0.8")
    view = e.bifurcation
    assert len(view.source.data["omega"]) == 0
    assert len(view.up_source.data["omega"]) > 0 and len(view.down_source.data["omega"]) > 0
    assert view.legend.visible
    assert e.diagram_status.object.startswith("complete: 7 ω values, swept up and down")
    values = np.linspace(2.5, 2.65, 7)
    p = view.run.params
    up, down = _chain(p, "omega", values[:3]), _chain(p, "omega", values[::-1][:3])
    for val, ref in zip(values[:3], up):
        np.testing.assert_allclose(rows_at(view.parts, val, 1), ref, rtol=0, atol=1e-8)
    for val, ref in zip(values[::-1][:3], down):
        np.testing.assert_allclose(rows_at(view.parts, val, -1), ref, rtol=0, atol=1e-8)
    head = e.downloads.bifurcation_csv().getvalue().splitlines()
    assert "omega,v,t,phase,direction" in head


def test_sweeping_up_and_down_shows_hysteresis(make_explorer):
    """r = 0.8 across [2.5, 2.8] (issue 9): the impact sets of the two chains differ at
    some value (compared as sets of the last impacts, to 1e-6)."""
    e = make_explorer(bif_sweep="both", bif_min="2.5", bif_max="2.8", bif_n="13", r="0.8")
    parts = e.bifurcation.parts

    def orbit(val, d):
        return set(np.round(rows_at(parts, val, d)[-12:], 6))

    values = np.linspace(2.5, 2.8, 13)
    assert any(orbit(val, 1) != orbit(val, -1) for val in values)
    assert orbit(values[0], 1) == orbit(values[0], -1)     # both on period-1 at 2.5


@pytest.mark.parametrize("mode,d", [("up", 1), ("down", -1)])
def test_one_direction_fills_its_renderer_only(make_explorer, mode, d):
    e = make_explorer(bif_sweep=mode, bif_min="2.5", bif_max="2.8", bif_n="7")
    view = e.bifurcation
    filled = {k: len(getattr(view, a).data["omega"]) > 0
              for k, a in ((0, "source"), (1, "up_source"), (-1, "down_source"))}
    assert filled == {0: False, 1: d == 1, -1: d == -1}
    assert view.legend is not None and not view.legend.visible


def test_tap_sets_the_swept_parameter(make_explorer):
    e = make_explorer(bif_min="0.1", bif_max="5", bif_n="400")
    fig = e.bifurcation.figure
    fig._trigger_event(Tap(model=fig, x=3.0, y=-0.5))
    step = 4.9 / 399
    assert abs(e.settings.omega - 3.0) <= step + 0.01
    assert e.bifurcation.marker.location == e.settings.omega
    e.settings.bif_param = "r"
    assert e.diagram.job.done.wait(60)
    fig._trigger_event(Tap(model=fig, x=0.4321, y=-0.5))
    assert abs(e.settings.r - 0.4321) <= 1 / 399
    assert e.bifurcation.marker.location == e.settings.r
    fig._trigger_event(Tap(model=fig, x=7.0, y=0.0))       # beyond the range: its end
    assert e.settings.r == 1.0


def test_tap_value_rounding():
    assert tap_value(3.00049, 0.1, 5.0, 400) == 3.0
    assert tap_value(-1.0, 0.1, 5.0, 400) == 0.1
    assert tap_value(0.43217, 0.0, 1.0, 400) == 0.4322


def test_hover_reads_value_and_velocity(make_explorer):
    e = make_explorer(bif_param="k", bif_n="5", **OWN_RANGE)
    assert e.bifurcation.hover.tooltips == [("k", "@omega{0.0000}"),
                                           ("impact velocity", "@v{0.0000}")]


@pytest.mark.parametrize("args,field", [
    ({"bif_param": "r", "bif_max": "2"}, "bif_max"), ({"bif_param": "x"}, "bif_param"),
    ({"bif_sweep": "sideways"}, "bif_sweep"), ({"bif_param": "m", "bif_min": "0"}, "bif_min"),
    ({"bif_param": "g", "x0": "0.1"}, "x0"), ({"bif_min": "3", "bif_max": "2"}, "bif_max"),
])
def test_bad_sweep_settings_are_named(args, field):
    values, errors = state.initial_settings(args)
    assert errors and errors[0].startswith(field + ":"), errors
    state.validate(values)
