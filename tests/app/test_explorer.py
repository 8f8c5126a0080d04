"""The app's state logic without a browser: build a session, change a setting, assert on
the views' ``source.data``. Numbers are checked against closed forms, not our output."""
import csv
import math

import numpy as np
import pytest

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
    gen, poincare = e.runner.generation, columns(e.poincare.source)
    e.settings.psi = 0.25
    for v, data in before.items():
        for name, col in data.items():
            assert getattr(e, v).source.data[name] is col, (v, name)
    assert e.runner.generation == gen
    new = np.asarray(e.poincare.source.data["x"])
    assert new.shape != np.shape(poincare["x"]) or not np.allclose(new, poincare["x"])


def test_omega_moves_the_marker_not_the_diagram(make_explorer):
    e = make_explorer()
    diagram, gen = columns(e.bifurcation.source), e.runner.generation
    displacement = columns(e.displacement.source)
    e.settings.omega = 2.8
    assert e.bifurcation.marker.location == 2.8
    assert e.runner.generation == gen
    for name, col in diagram.items():
        assert e.bifurcation.source.data[name] is col
    assert e.displacement.source.data["x"] is not displacement["x"]
    assert set(e.bifurcation.current.data["omega"]) == {2.8}


@pytest.mark.parametrize("name,value", [("r", 0.6), ("c", 0.1), ("g", -0.1), ("m", 1.5),
                                         ("k", 2.0)])
def test_physics_change_recomputes_scene_and_restarts_diagram(make_explorer, name, value):
    e = make_explorer()
    gen, x = e.runner.generation, e.displacement.source.data["x"]
    e.settings.param.update(**{name: value})
    assert e.runner.generation == gen + 1
    assert e.displacement.source.data["x"] is not x
    assert e.runner.done.wait(60)
    assert f"{name} = {value:g}" in e.bifurcation.figure.title.text
    assert len(e.bifurcation.source.data["omega"]) > 0


def test_superseded_diagram_is_cancelled(make_explorer):
    e = make_explorer()
    for r in (0.1, 0.2, 0.3, 0.9):
        e.settings.r = r
    assert e.runner.done.wait(60)
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
    x, gen = e.displacement.source.data["x"], e.runner.generation
    e.settings.m = -1.0
    assert "m" in e.message and e.message_pane.visible
    assert e.displacement.source.data["x"] is x and e.runner.generation == gen
    e.settings.m = None                               # an emptied input box
    assert "m" in e.message
    e.settings.m = 1.0
    assert e.message == "" and not e.message_pane.visible


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
