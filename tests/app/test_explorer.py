"""The app's state logic without a browser: build a session, change a setting, assert on
the views' ``source.data``. Numbers are checked against closed forms, not our output."""
import csv
import math

import numpy as np
import pytest

from app import state
from app.scenes import BY_KEY, SCENES


def columns(source):
    return {k: v for k, v in source.data.items()}


def test_five_views_hold_data(make_explorer):
    e = make_explorer()
    assert e.message == ""
    for view in (e.displacement, e.phase, e.impact_map, e.poincare, e.bifurcation):
        data = view.source.data
        assert all(len(col) > 0 for col in data.values()), type(view).__name__
    assert "Motion:" in e.badge.object and "ms" in e.badge.object
    assert e.diagram_status.object.startswith("complete")


def test_time_series_respect_the_point_budget(make_explorer):
    e = make_explorer(omega="0.2")            # chattering: many impacts
    n = len(e.displacement.source.data["t"])
    assert n <= 4000 + 2 * 2000
    assert np.all(np.diff(e.displacement.source.data["t"]) >= 0)


def test_psi_resamples_the_poincare_map_only(make_explorer):
    e = make_explorer()
    before = {v: columns(getattr(e, v).source)
              for v in ("displacement", "phase", "impact_map", "bifurcation")}
    gen, poincare = e.diagram.job.generation, columns(e.poincare.source)
    e.settings.psi = 0.25
    for v, data in before.items():
        for name, col in data.items():
            assert getattr(e, v).source.data[name] is col, (v, name)
    assert e.diagram.job.generation == gen
    new = np.asarray(e.poincare.source.data["x"])
    assert new.shape != np.shape(poincare["x"]) or not np.allclose(new, poincare["x"])


def test_omega_moves_the_marker_not_the_diagram(make_explorer):
    e = make_explorer()
    diagram, gen = columns(e.bifurcation.source), e.diagram.job.generation
    displacement = columns(e.displacement.source)
    e.settings.omega = 2.8
    assert e.bifurcation.marker.location == 2.8
    assert e.diagram.job.generation == gen
    for name, col in diagram.items():
        assert e.bifurcation.source.data[name] is col
    assert e.displacement.source.data["x"] is not displacement["x"]
    assert set(e.bifurcation.current.data["omega"]) == {2.8}


@pytest.mark.parametrize("name,value", [("r", 0.6), ("c", 0.1), ("g", -0.1), ("m", 1.5),
                                         ("k", 2.0)])
def test_physics_change_recomputes_scene_and_restarts_diagram(make_explorer, name, value):
    e = make_explorer()
    gen, x = e.diagram.job.generation, e.displacement.source.data["x"]
    e.settings.param.update(**{name: value})
    assert e.diagram.job.generation == gen + 1
    assert e.displacement.source.data["x"] is not x
    assert e.diagram.job.done.wait(60)
    assert f"{name} = {value:g}" in e.bifurcation.figure.title.text
    assert len(e.bifurcation.source.data["omega"]) > 0


def test_superseded_diagram_is_cancelled(make_explorer):
    e = make_explorer()
    for r in (0.1, 0.2, 0.3, 0.9):
        e.settings.r = r
    assert e.diagram.job.done.wait(60)
    assert "r = 0.9" in e.bifurcation.figure.title.text
    values = np.unique(e.bifurcation.source.data["omega"])
    assert values.size <= 40                  # one diagram, not four stacked


def test_no_impact_motion_matches_the_linear_closed_form(make_explorer):
    # Wall far below the motion: steady state x = X cos(w t - phi) with
    # X = 1 / sqrt((k - m w^2)^2 + (2 c w)^2), tan phi = 2 c w / (k - m w^2).
    # After 250 s the transient has decayed by exp(-c t / m) ~ 4e-6.
    m, c, k, w = 1.0, 0.05, 1.0, 1.3
    e = make_explorer(g="-10", m=str(m), c=str(c), k=str(k), omega=str(w), psi="0.7")
    X = 1 / math.hypot(k - m * w * w, 2 * c * w)
    phi = math.atan2(2 * c * w, k - m * w * w)
    x = np.asarray(e.displacement.source.data["x"])
    assert x.max() == pytest.approx(X, rel=2e-3)      # sampled maximum, 4000 samples
    assert len(e.impact_map.source.data["v"]) == 0
    xs = np.asarray(e.poincare.source.data["x"])
    assert np.allclose(xs, X * math.cos(w * 0.7 - phi), atol=1e-4)


def test_fig2_is_one_point_in_both_maps(make_explorer):
    e = make_explorer()
    e.load_scene("fig2")
    for view in (e.impact_map, e.poincare):
        v = np.asarray(view.source.data["v"])
        assert v.size > 10 and np.ptp(v) < 1e-6
    x = np.asarray(e.displacement.source.data["x"])
    assert x.min() >= -1e-12                         # never through the wall at g = 0


def test_bad_widget_input_keeps_the_last_scene(make_explorer):
    e = make_explorer()
    x, gen = e.displacement.source.data["x"], e.diagram.job.generation
    e.settings.m = -1.0
    assert "m: -1 — must be > 0" in e.message and e.message_pane.visible
    assert e.displacement.source.data["x"] is x and e.diagram.job.generation == gen
    assert e.settings.m == 1.0                        # the box shows what is applied
    e.settings.m = None                               # an emptied input box
    assert "m: a value is required" in e.message and e.settings.m == 1.0
    e.settings.m = 2.0
    assert e.message == "" and not e.message_pane.visible and e.run.params.m == 2.0


@pytest.mark.parametrize("name,value,allowed", [
    ("omega", 0.0, "(0, 1000]"), ("omega", 1e6, "(0, 1000]"), ("r", 1.5, "[0, 1]"),
    ("bif_n", 1, "[2, 2000]"), ("t_end", 1e9, "(0, 20000]")])
def test_every_refused_value_is_named_with_its_range_and_the_box_shows_the_applied(
        make_explorer, name, value, allowed):
    e = make_explorer()
    before = state.applied(e.run)
    setattr(e.settings, name, value)
    assert e.message.startswith(f"Not applied — {name}: {value:g} — ")
    assert allowed in e.message
    assert state.applied(e.run) == before and getattr(e.settings, name) == before[name]


@pytest.mark.parametrize("name,value", [("omega", 20.0), ("omega", 1000.0), ("c", 100.0)])
def test_values_the_core_accepts_are_applied_beyond_the_sliders(make_explorer, name, value):
    e = make_explorer(t_end="20", t_record="10")
    setattr(e.settings, name, value)
    assert e.message == "" and getattr(e.run.params, name) == value


def test_a_slider_step_sum_is_applied_without_moving_the_slider_back(make_explorer):
    """Keyboard steps on a slider add up in binary (2.01 + 0.01 = 2.0199999999999996).
    The run takes the value on the step grid; writing it back would reset a slider the
    user is still moving, losing the steps made meanwhile. A value truly off the grid
    is still shown as applied."""
    e = make_explorer()
    stepped = 2.01 + 0.01
    assert stepped != 2.02
    e.settings.omega = stepped
    assert e.run.params.omega == 2.02 and e.settings.omega == stepped
    e.settings.omega = 2.0234
    assert e.run.params.omega == 2.02 and e.settings.omega == 2.02


def test_garbage_url_shows_message_and_defaults(make_explorer):
    e = make_explorer(omega="banana", r="0.5")
    assert "omega" in e.message and e.message_pane.visible
    assert e.run.params.omega == 2.0 and e.run.params.r == 0.5


@pytest.mark.parametrize("key", [s.key for s in SCENES])
def test_every_scene_loads(make_explorer, key):
    e = make_explorer()
    e.load_scene(key)
    sc = BY_KEY[key]
    for name, value in sc.changes.items():
        assert getattr(e.settings, name) == value
    assert e.message == ""
    assert e.caption.object == sc.caption
    if key.startswith("fig7"):
        # the paper's phi = (2j-1) pi / (4 omega), in time units
        j = "abcd".index(key[-1]) + 1
        assert e.run.psi == pytest.approx((2 * j - 1) * math.pi / (4 * 2.8), rel=1e-12)


def read_csv(buf):
    lines = buf.getvalue().splitlines()
    body = [line for line in lines if not line.startswith("#")]
    rows = list(csv.reader(body))
    return rows[0], np.array(rows[1:], dtype=float)


def csv_settings(buf) -> dict:
    """The ``# name = value`` block at the top of a CSV download."""
    out = {}
    for line in buf.getvalue().splitlines():
        if not line.startswith("#"):
            break
        name, _, value = line[1:].partition("=")
        out[name.strip()] = value.strip()
    return out


def test_csv_files_start_with_the_settings_they_were_computed_with(make_explorer):
    e = make_explorer(omega="2.81", r="0.6", c="0.07", g="0.1", m="1.5", k="2",
                      t_end="400", t_record="300", method="rk45")
    import importlib.metadata
    for make in (e.downloads.impacts_csv, e.downloads.poincare_csv,
                 e.downloads.bifurcation_csv):
        buf = make()
        got = csv_settings(buf)
        names = list(got)
        assert names[:10] == ["m", "c", "k", "g", "r", "omega", "psi", "t_end", "t_record",
                              "method"] and names[-1] == "version"
        # the diagram adds its start and sweep and names the method it ran (exact)
        extra = names[10:-1]
        if make == e.downloads.bifurcation_csv:
            assert {"x0", "v0", "bif_param", "bif_sweep", "bif_n"} <= set(extra)
            assert got["method"] == "exact" and got["bif_param"] == "omega"
            got["method"] = "rk45"       # the scene's method, checked below
        else:                # the start, the section as a fraction of T, rk45's options
            assert extra == ["psi_over_T", "x0", "v0", "rtol", "atol"]
            assert (float(got["x0"]), float(got["rtol"])) == (0.1, 1e-6)
        assert {n: float(got[n]) for n in ("m", "c", "k", "g", "r", "omega", "t_end",
                                           "t_record")} == {
            "m": 1.5, "c": 0.07, "k": 2.0, "g": 0.1, "r": 0.6, "omega": 2.81,
            "t_end": 400.0, "t_record": 300.0}
        assert float(got["psi"]) == 0.0 and got["method"] == "rk45"
        assert got["version"] == importlib.metadata.version("impact-explorer")
        # one header row follows, then numbers only
        head, data = read_csv(buf)
        assert len(head) == data.shape[1] and len(data) > 0


def test_csv_downloads_hold_what_is_shown(make_explorer):
    e = make_explorer()
    head, data = read_csv(e.downloads.impacts_csv())
    assert head == ["t", "phase", "v_before", "v_after"]
    assert np.allclose(data[:, 2], e.impact_map.source.data["v"])
    assert np.allclose(data[:, 3], -0.8 * data[:, 2])
    head, data = read_csv(e.downloads.poincare_csv())
    assert head == ["t", "x", "v"] and np.allclose(data[:, 1], e.poincare.source.data["x"])
    head, data = read_csv(e.downloads.bifurcation_csv())
    assert head == ["omega", "v", "t", "phase"]
    shown = np.asarray(e.bifurcation.source.data["omega"])
    assert len(data) >= len(shown)
    assert np.allclose(np.unique(data[:, 0]), np.unique(shown), rtol=1e-9)
    assert e.downloads.widgets[0].filename == "impacts_omega2_r0.8_c0.05_g0.csv"


def test_link_the_core_refuses_falls_back_to_defaults(make_explorer):
    # dt = 10 passes the app's checks but not the core's RK4 stability limit
    e = make_explorer(method="rk4", dt="10")
    assert "dt" in e.message and e.message_pane.visible
    assert e.run is not None and e.run.method == "exact"
    assert len(e.displacement.source.data["x"]) > 0


@pytest.mark.parametrize("key,paper", [
    ("fig2", "1-impact period-1"),          # Lee, Fig. 2 caption
    ("fig4", "complete chattering"),        # Fig. 4: complete chattering, period-1
    ("fig5", "3-impact period-2"),          # Fig. 5 caption (on the longer window)
    ("fig6", "chaotic"),                    # Fig. 6: "∞-impact period-∞"
])
def test_scene_badges_say_what_the_paper_says(make_explorer, key, paper):
    e = make_explorer()
    e.load_scene(key)
    assert paper in e.badge.object


def test_extreme_physics_is_cut_short_with_a_message(make_explorer):
    # m = 1e-6: natural frequency 1000 rad/s, hundreds of thousands of impacts
    import time
    t0 = time.perf_counter()
    e = make_explorer(m="1e-6", bif_n="4")
    assert time.perf_counter() - t0 < 10
    assert "⚠" in e.badge.object and "limit" in e.badge.object


def test_diagram_stops_at_its_wall_time(make_explorer, monkeypatch):
    from app import diagram
    monkeypatch.setattr(diagram, "DIAGRAM_WALL_TIME", 0.0)
    diagram.CACHE.clear()                     # not a diagram computed before
    e = make_explorer(bif_n="200")
    assert e.diagram_status.object.startswith("stopped at the time limit")
    assert "partial" in e.bifurcation.figure.title.text


def test_accuracy_readout_compares_the_three_methods():
    from app import accuracy, state
    run = state.validate(state.defaults())
    rows = accuracy.compare_methods(run)
    assert [r.method for r in rows] == ["exact", "rk4", "rk45"]
    assert rows[0].dt_max == 0 and rows[0].compared > 5 and rows[0].missed == 0
    for r in rows[1:]:
        assert r.compared == rows[0].compared and r.missed == r.extra == 0
        assert r.dt_max < 1e-3 and r.seconds > 0       # loose: a smoke test, not a bound
    html = accuracy.to_html(rows)
    assert "rk45" in html and "<table" in html


def test_accuracy_readout_reports_an_unstable_rk4_step():
    from app import accuracy, state
    run = state.validate({**state.defaults(), "dt": 10.0})
    rk4 = accuracy.compare_methods(run)[1]
    assert rk4.method == "rk4" and "stability" in rk4.message


def test_time_plot_is_sampled_for_the_window_on_screen(make_explorer):
    """t_end = 20000 s: the scene's 4000 samples would be one per 5 s (T = 2.24 s).
    The window shown gets >= 48 samples per period and every impact in it as an exact
    corner (x = g at the scene's own impact times, bit for bit)."""
    from app import compute
    e = make_explorer(omega="2.81", t_end="20000", t_record="250")
    T = e.run.params.T
    t = np.asarray(e.displacement.source.data["t"])
    assert t[0] == pytest.approx(20000 - 8 * T) and t[-1] == pytest.approx(20000)
    assert np.max(np.diff(t)) <= T / compute.SAMPLES_PER_PERIOD * 1.001
    cols = compute.window_columns(e.run, 19000.0, 19020.0, 800)
    t, x = cols["t"], cols["x"]
    imp = np.asarray(e.scene.impacts["t"])
    inside = imp[(imp > 19000) & (imp < 19020)]
    assert inside.size > 0
    for ti in inside:
        at = np.flatnonzero(t == ti)
        assert at.size == 2 and np.all(x[at] == 0.0), ti    # the corner: (g, v-), (g, v+)
    # zoomed all the way out: the envelope per pixel column, not a zig-zag
    env = compute.window_columns(e.run, 250.0, 20000.0, 800)
    assert len(env["t"]) <= 2 * 800 and np.all(np.isnan(env["v"]))
    # it spans the motion: down to the wall, up to (within 27 samples per period of
    # chord error, < 1 %) the highest x of the finely sampled 20 s above
    assert env["x"].min() == 0.0 and env["x"].max() >= 0.99 * x.max()


def test_window_samples_match_the_linear_closed_form(make_explorer):
    """No impacts (wall far away): x(t) in a zoomed window is the steady state
    X cos(ωt − φ) of the linear oscillator (the transient has decayed by e^-20)."""
    from app import compute
    m, c, k, w = 1.0, 0.05, 1.0, 1.3
    e = make_explorer(g="-10", m=str(m), c=str(c), k=str(k), omega=str(w))
    cols = compute.window_columns(e.run, 400.0, 420.0, 600)
    X = 1 / math.hypot(k - m * w * w, 2 * c * w)
    phi = math.atan2(2 * c * w, k - m * w * w)
    assert len(cols["t"]) >= 20 / (2 * math.pi / w) * compute.SAMPLES_PER_PERIOD
    assert np.allclose(cols["x"], X * np.cos(w * cols["t"] - phi), atol=1e-6)


def test_compare_mode_shows_fig3_and_fig7_on_shared_fixed_axes(make_explorer):
    """Built only when opened; the six diagrams and four sections come from the shared
    caches and fit the fixed axes; every panel of a figure shares its ranges."""
    from app import compute, diagram, state as st
    from app.scenes import BY_KEY as SC
    from app.views import compare
    e = make_explorer()
    assert e.compare.view is None
    e.settings.mode = "compare"
    for job in e.compare.jobs:
        assert job.done.wait(120), job.name
    diagrams = [e.compare.view.diagrams[k] for k in compare.DIAGRAMS]
    assert len({id(f.x_range) for _, f in diagrams}) == 1
    assert len({id(f.y_range) for _, f in diagrams}) == 1
    lo, hi = compare.V_RANGE
    for key, (src, fig) in zip(compare.DIAGRAMS, diagrams):
        v = np.asarray(src.data["v"])
        assert v.size > 100 and lo <= v.min() and v.max() <= hi, (key, v.min(), v.max())
        run = st.validate({**st.defaults(), **SC[key].settings()})
        assert run.diagram_key() in diagram.CACHE          # computed once, shared
        assert (fig.y_range.start, fig.y_range.end) == compare.V_RANGE   # fixed
    for key in compare.SECTIONS:
        src, fig = e.compare.view.sections[key]
        run = st.validate({**st.defaults(), **SC[key].settings()})
        ref = compute.section_columns(run)
        assert np.array_equal(src.data["x"], ref["x"]) and len(ref["x"]) > 50
        assert compare.SECTION_X[0] <= min(ref["x"]) and max(ref["x"]) <= compare.SECTION_X[1]
        assert compare.SECTION_V[0] <= min(ref["v"]) and max(ref["v"]) <= compare.SECTION_V[1]
    e.settings.mode = "explore"


def test_pin_keeps_the_maps_as_an_overlay(make_explorer):
    e = make_explorer()
    before = np.asarray(e.impact_map.source.data["v"]).copy()
    e.controls.pin_toggle.value = True
    e.settings.omega = 2.5
    e.scene_job.done.wait(30)
    assert np.array_equal(e.impact_map.pinned.data["v"], before)
    assert not np.array_equal(e.impact_map.source.data["v"], before)
    e.controls.pin_toggle.value = False
    assert len(e.impact_map.pinned.data["v"]) == 0 and len(e.poincare.pinned.data["x"]) == 0


def test_every_scene_view_has_a_hover_readout(make_explorer):
    from bokeh.models import HoverTool
    e = make_explorer()
    for view in (e.displacement, e.phase, e.impact_map, e.poincare, e.animation):
        hovers = [t for t in view.figure.tools if isinstance(t, HoverTool)]
        assert hovers, view.key
        for h in hovers:     # each reads a renderer of its own figure
            assert h.renderers and all(r in view.figure.renderers for r in h.renderers)


@pytest.mark.parametrize("view_key", ["phase", "poincare"])
def test_tap_starts_the_motion_there(make_explorer, view_key):
    """A tap at (x, ẋ) sets x0, v0 (4 significant digits); beyond the wall x0 = g."""
    from types import SimpleNamespace
    from bokeh.events import Tap
    e = make_explorer(g="0.25")
    fig = getattr(e, view_key).figure
    handler = fig._event_callbacks[Tap.event_name][0]
    handler(SimpleNamespace(x=0.73214, y=-0.41236))
    e.scene_job.done.wait(30)
    assert (e.settings.x0, e.settings.v0) == (0.7321, -0.4124)
    assert (e.run.x0, e.run.v0) == (0.7321, -0.4124)
    handler(SimpleNamespace(x=0.1, y=0.5))             # x < g = 0.25
    e.scene_job.done.wait(30)
    assert (e.run.x0, e.run.v0) == (0.25, 0.5)


def test_pinned_maps_stay_in_view_when_the_axes_rescale(make_explorer):
    """Pin at ω = 2, jump to ω = 0.2 (T ≈ 31 s, slow impacts): the rescaled axes still
    hold every pinned point."""
    e = make_explorer()
    e.controls.pin_toggle.value = True
    e.settings.omega = 0.2
    e.scene_job.done.wait(30)
    for view, (cx, cy) in ((e.impact_map, ("phase", "v")), (e.poincare, ("x", "v"))):
        f, pinned = view.figure, view.pinned.data
        assert len(pinned[cx]) > 0
        assert f.x_range.start <= min(pinned[cx]) and max(pinned[cx]) <= f.x_range.end, view.key
        assert f.y_range.start <= min(pinned[cy]) and max(pinned[cy]) <= f.y_range.end, view.key


def test_scene_csvs_carry_the_start_and_the_section_in_both_units(make_explorer):
    from app.downloads import read_header
    e = make_explorer(omega="2.8", psi="0.3", x0="0.25", v0="-0.5")
    T = 2 * math.pi / 2.8
    for text in (e.downloads.impacts_csv().read(), e.downloads.poincare_csv().read()):
        h = read_header(text)
        assert (float(h["x0"]), float(h["v0"])) == (0.25, -0.5)
        assert float(h["psi"]) == pytest.approx(0.3, rel=1e-9)              # time (s)
        assert float(h["psi_over_T"]) == pytest.approx(0.3 / T, rel=1e-9)   # of the period
    h = read_header(make_explorer(g="0.1").downloads.impacts_csv().read())
    assert float(h["x0"]) == 0.1                    # empty x0: at the wall, max(0, g)
