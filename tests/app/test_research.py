"""Regime map and basins views without a browser: streaming, cancelling, budgets, taps.

References: ``il.classify`` of single ``il.simulate`` runs for map cells; for the basins,
the scene started at a tapped cell (its own simulation and classification) must be the
attractor the cell is coloured with; the period-1 fixed point at r = 0.8, omega = 2.62
is checked in the core's tests against scipy.optimize.root.
"""
import io

import numpy as np
import pytest
from bokeh.events import Tap

import impactlib as il
from impactlib.analysis.classify import describe
from app import research, state
from app.research_panel import BASINS, MAP

PAPER_R08 = {"r": "0.8", "omega": "2.62"}


def tap(view, x, y):
    view.figure._trigger_event(Tap(model=view.figure, x=x, y=y))


def test_research_card_is_built_only_when_opened(make_explorer):
    e = make_explorer()
    assert not e.research.built and len(e.research.room.objects) == 0
    e.settings.mode = "research"                # opening computes the open tab (the map)
    assert e.research.built
    assert e.research.job.done.wait(120)
    assert e.research.status[MAP].object.startswith("complete")
    assert e.research.running is None


def test_regime_map_streams_rows_that_agree_with_single_runs(make_explorer, monkeypatch):
    e = make_explorer(map_n="24")
    blocks = []
    rows = e.research.rows
    monkeypatch.setattr(e.research, "rows", lambda kind, b: (blocks.append(b), rows(kind, b)))
    e.research.compute(MAP)
    view = e.research.views[MAP]
    assert len(blocks) >= 2 and blocks[0].rows_done < 24 and blocks[-1].rows_done == 24
    assert [b.start for b in blocks] == sorted(b.start for b in blocks)
    assert not np.isnan(view.image).any()
    assert view.source.data["image"][0].shape == (24, 24)
    assert e.research.status[MAP].object.startswith("complete: 24 rows")
    assert "ie-legend" in e.research.legend[MAP].object
    req = view.request
    names = blocks[-1].labels                   # class index -> label
    rng = np.random.default_rng(9)
    for iy, ix in rng.integers(0, 24, size=(6, 2)):
        p = req.run.params.replace(**{req.name_x: req.values_x[ix], req.name_y: req.values_y[iy]})
        ref = il.classify(il.simulate(p, t_end=500.0, t_record=250.0))
        drawn = names[int(view.image[iy, ix])]
        if ref.kind == "periodic" and drawn == "other periodic":
            # beyond the cut-off: every named periodic class is taken, none is this one
            assert ref.label not in names and len(names) == len(research.PALETTE), (iy, ix)
        elif ref.kind == "periodic":
            assert drawn == ref.label, (iy, ix)
        else:
            assert drawn == ref.kind, (iy, ix)


def test_regime_map_is_cancellable(make_explorer, monkeypatch):
    e = make_explorer(map_n="60")
    calls = []
    # each block of the library's stream (il.iter_regime_map) is one regime_map call
    from impactlib.sweeps import diagrams
    real = diagrams.regime_map
    monkeypatch.setattr(diagrams, "regime_map", lambda *a, **k: (calls.append(1),
                                                                 real(*a, **k))[1])
    rows = e.research.rows

    def first_then_cancel(kind, block):
        rows(kind, block)
        e.research.cancel()

    monkeypatch.setattr(e.research, "rows", first_then_cancel)
    e.research.compute(MAP)
    assert len(calls) == 1                      # no block computed after the cancel
    view = e.research.views[MAP]
    assert 0 < view.rows_done < 60 and np.isnan(view.image).any()
    assert e.research.status[MAP].object.startswith("cancelled after")
    assert e.research.running is None and e.research.job.done.is_set()


def test_basins_supersede_the_map(make_explorer, monkeypatch):
    """One heavy job per session: asking for the basins stops the map."""
    e = make_explorer(map_n="60", basins_n="20", **PAPER_R08)
    rows = e.research.rows
    asked = []

    def switch(kind, block):
        rows(kind, block)
        if kind == MAP and not asked:
            asked.append(1)
            e.research.compute(BASINS)

    monkeypatch.setattr(e.research, "rows", switch)
    e.research.compute(MAP)
    assert e.research.job.done.wait(60)
    assert e.research.status[MAP].object.startswith("cancelled after")
    assert e.research.status[BASINS].object.startswith("complete: 20 rows")


def test_regime_map_tap_sets_both_parameters(make_explorer):
    e = make_explorer(map_n="12")
    e.research.compute(MAP)
    view = e.research.views[MAP]
    assert view.current.data == {"x": [2.0], "y": [0.8]}
    tap(view, 2.8, 0.6)
    assert (e.settings.omega, e.settings.r) == (2.8, 0.6)
    assert e.scene.run.params.omega == 2.8 and e.scene.run.params.r == 0.6
    assert view.current.data == {"x": [2.8], "y": [0.6]}


def test_regime_map_in_other_parameters(make_explorer):
    e = make_explorer(map_n="6", map_x="c", map_y="k")
    e.research.compute(MAP)
    view = e.research.views[MAP]
    assert view.figure.xaxis.axis_label.startswith("damping c")
    assert (view.figure.x_range.start < 0 < view.figure.x_range.end)
    tap(view, 0.2, 1.5)
    assert (e.settings.c, e.settings.k) == (0.2, 1.5)


def test_basins_tap_starts_the_scene_on_that_attractor(make_explorer):
    e = make_explorer(basins_n="30", **PAPER_R08)
    e.research.compute(BASINS)
    view = e.research.views[BASINS]
    assert e.research.status[BASINS].object.startswith("complete: 30 rows")
    labels = [a.label for a in view.attractors]
    assert "1-impact period-1" in labels and len(labels) >= 2, labels
    assert view.request.x_range[0] == 0.0                    # from the wall g = 0
    assert not np.isnan(view.image).any()
    for target in ("1-impact period-1", next(lab for lab in labels if lab != "1-impact period-1")):
        k = labels.index(target) + 1
        iv, ix = np.argwhere(view.image == k)[len(np.argwhere(view.image == k)) // 2]
        x, v = view.xs[ix], view.vs[iv]
        tap(view, x, v)
        dx, dv = view.xs[1] - view.xs[0], view.vs[1] - view.vs[0]
        assert abs(e.settings.x0 - x) <= dx / 10 and abs(e.settings.v0 - v) <= dv / 10
        assert e.scene.run.x0 == e.settings.x0
        assert e.scene.label == target, (x, v, e.scene.label)
        assert view.start.data == {"x": [e.settings.x0], "v": [e.settings.v0]}


@pytest.mark.parametrize("args,field", [
    ({"map_n": "301"}, "map_n"), ({"map_n": "1"}, "map_n"), ({"basins_n": "201"}, "basins_n"),
    ({"basins_n": "1e9"}, "basins_n"), ({"map_x": "r"}, "map_y"), ({"map_y": "t"}, "map_y"),
])
def test_url_cannot_exceed_the_budgets(args, field):
    values, errors = state.initial_settings(args)
    assert errors and errors[0].startswith(field + ":"), errors
    run = state.validate(values)
    assert run.map_n <= 300 and run.basins_n <= 200


def test_wall_time_ends_with_partial_results_and_a_message():
    run = state.validate({**state.defaults(), "map_n": 40})
    blocks = list(research.map_rows(research.map_request(run), wall_time=0.0))
    assert len(blocks) == 1 and blocks[0].rows_done < 40
    assert blocks[0].message.startswith("stopped at the time limit")
    req = research.BasinsRequest(run, (0.0, 1.0), (-1.0, 1.0), 40)
    blocks = list(research.basins_rows(req, wall_time=1e-9))
    assert blocks[-1].rows_done < 40 and "time_limit" in blocks[-1].message


def test_refused_settings_show_the_cores_message(make_explorer):
    """r = 1, c = 0: nothing attracts; and a start window the core refuses."""
    e = make_explorer(basins_n="8", r="1", c="0")
    e.research.compute(BASINS)
    text = e.research.status[BASINS].object
    assert "no dissipation" in text, text
    req = research.BasinsRequest(e._wanted, (-1.0, 1.0), (-1.0, 1.0), 8)   # x below g
    e.research.started(BASINS, req)
    e.research.job.submit((BASINS, req))
    assert e.research.status[BASINS].object.startswith("not computed — ValueError")
    assert "x_range" in e.research.status[BASINS].object


# -- CSV downloads ---------------------------------------------------------------------

SETTING_LINES = ["m", "c", "k", "g", "r", "omega", "psi", "t_end", "t_record", "method"]


def parse(buf):
    """(settings block, header row, numeric rows) of a CSV download; pandas agrees."""
    import pandas as pd
    from app.downloads import read_header
    text = buf.getvalue()
    lines = text.splitlines()
    body = [line for line in lines if not line.startswith("#")]
    assert all(line.startswith("#") for line in lines[:len(lines) - len(body)])
    head = body[0].split(",")
    data = np.array([row.split(",") for row in body[1:]], dtype=float).reshape(-1, len(head))
    frame = pd.read_csv(io.StringIO(text), comment="#")
    assert list(frame.columns) == head and frame.shape == data.shape
    return read_header(text), head, data


def test_csv_headers_name_every_setting_and_parse(make_explorer):
    import importlib.metadata
    e = make_explorer(map_n="8", basins_n="10", bif_sweep="both", bif_min="2.5",
                      bif_max="2.8", bif_n="7", method="rk45", c="0.07", **PAPER_R08)
    e.research.compute(MAP)
    e.research.compute(BASINS)
    version = importlib.metadata.version("impact-explorer")
    bif = parse(e.downloads.bifurcation_csv())
    rmap = parse(e.downloads.regime_map_csv(e.research.views[MAP]))
    bas = parse(e.downloads.basins_csv(e.research.views[BASINS]))
    for got, _, _ in (bif, rmap, bas):
        assert list(got)[:10] == SETTING_LINES and list(got)[-1] == "version"
        assert got["version"] == version
        assert {n: float(got[n]) for n in ("m", "c", "k", "g", "r", "omega", "t_end",
                                           "t_record")} == {
            "m": 1.0, "c": 0.07, "k": 1.0, "g": 0.0, "r": 0.8, "omega": 2.62,
            "t_end": 500.0, "t_record": 250.0}
        assert got["method"] == "exact"          # what the sweeps use, not the scene's rk45
    got, head, data = bif
    assert got["bif_sweep"] == "both" and got["bif_param"] == "omega"
    assert (float(got["bif_min"]), float(got["bif_max"]), int(got["bif_n"])) == (2.5, 2.8, 7)
    assert head == ["omega", "v", "t", "phase", "direction"]
    assert set(data[:, 4]) == {1.0, -1.0}
    got, head, data = rmap
    assert head == ["omega", "r", "m", "n", "class"] and data.shape[0] == 64
    assert (got["map_x"], got["map_y"], got["sweep"]) == ("omega", "r", "independent")
    assert float(got["map_x_min"]) == 0.1 and float(got["map_y_max"]) == 1.0
    for m, n, k in data[:, 2:5].astype(int):
        motion = research.describe(int(m), int(n))
        label = got[f"class {k}"]
        assert label in (motion.label, motion.kind, "other periodic", "other")
    got, head, data = bas
    assert head == ["x0", "v0", "attractor"] and data.shape[0] == 100
    assert float(got["phase"]) == 0.0 and int(got["basins_n"]) == 10
    found = {int(a) for a in data[:, 2]} - {-1}
    assert all(f"attractor {a}" in got for a in found)
    assert any("1-impact period-1" in got[f"attractor {a}"] for a in found)
    assert data[:, 0].min() >= float(got["x_min"]) and data[:, 0].max() <= float(got["x_max"])


def test_a_picture_says_when_its_settings_changed(make_explorer):
    e = make_explorer(map_n="6", basins_n="6", **PAPER_R08)
    e.research.compute(MAP)
    e.research.compute(BASINS)
    m, b = e.research.views[MAP].figure.title, e.research.views[BASINS].figure.title
    assert "settings changed" not in m.text + b.text
    e.settings.param.update(omega=2.7, r=0.7)         # the map's own axes: still valid
    assert "settings changed" not in m.text and "settings changed" in b.text
    e.settings.c = 0.06
    assert "settings changed" in m.text
    e.research.compute(MAP)
    assert "settings changed" not in m.text


def test_map_colours_do_not_depend_on_the_blocks_the_rows_came_in():
    """The app streams a map in blocks sized by the measured rate, so the same link
    arrives in other blocks from one visit to the next: each periodic class keeps the
    colour of its first cell, row by row (checked against that order computed from the
    whole grid at once), whatever the blocks, and so does the legend's cut-off."""
    rng = np.random.default_rng(7)
    # 16 periodic classes (more than the palette's 12) and two fixed ones, scattered
    codes = [(1, 1), (1, 2), (2, 1), (2, 2), (3, 3), (1, 3), (2, 4), (4, 2), (3, 1),
             (1, 4), (2, 3), (3, 2), (4, 4), (5, 5), (1, 5), (2, 5), (0, 0), (-1, 0)]
    pick = rng.integers(0, len(codes), size=(40, 25))
    impacts = np.array([[codes[k][0] for k in row] for row in pick])
    period = np.array([[codes[k][1] for k in row] for row in pick])
    order = []                                  # periodic classes by first cell, row-major
    for m, n in zip(impacts.ravel(), period.ravel()):
        if m > 0 and n > 0 and (m, n) not in order:
            order.append((m, n))
    expected = {describe(m, n).label for m, n in order[:len(research.PERIODIC_COLOURS)]}
    legends = []
    for sizes in ([40], [1] * 40, [3, 7, 11, 19], [25, 15]):
        classes, a = research.RegimeClasses(), 0
        for size in sizes:
            classes.classes(impacts[a:a + size], period[a:a + size])
            a += size
        coloured = set(classes.labels[len(research.FIXED_CLASSES):])
        assert coloured == expected, sizes
        legends.append(classes.legend())
    assert all(leg == legends[0] for leg in legends)
