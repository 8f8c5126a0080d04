"""Boundary curves over the regime map without a browser: the switch, the three renderers,
cancelling when the map's settings change, the shared result, the URL name.

Reference: each drawn period-doubling curve is checked at spread points by central
differences of the simulator's n-period map (a multiplier at -1), independent of
il.boundary's equations."""
import numpy as np
import pytest

import impactlib as il
from app import boundaries, state
from app.research_panel import MAP


@pytest.fixture
def few_seeds(monkeypatch):
    monkeypatch.setattr(boundaries, "SEEDS", 2)        # seeds at omega = 1.73 and 3.37
    boundaries.CACHE.clear()
    yield
    boundaries.CACHE.clear()


def fd_multipliers(p, x, v, n, h=1e-6):
    def f(x, v):
        sol = il.simulate(p, t_end=n * p.T, t_record=0.0, x0=x, v0=v)
        return np.array(sol.final[1:3])
    J = np.column_stack([(f(x + h, v) - f(x - h, v)) / (2 * h),
                         (f(x, v + h) - f(x, v - h)) / (2 * h)])
    return np.linalg.eigvals(J)


def test_url_name_and_default():
    assert state.validate(state.defaults()).boundaries is False
    run = state.validate({**state.defaults(), "boundaries": True})
    assert run.boundaries is True and state.to_query(run)["boundaries"] == "1"
    assert state.initial_settings({"boundaries": "1"})[0]["boundaries"] is True


def test_switch_draws_the_three_kinds_and_a_settings_change_cancels(make_explorer,
                                                                   few_seeds):
    e = make_explorer(map_n="8", boundaries="1")
    e.research.compute(MAP)
    assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(120)
    fig = e.research.views[MAP].figure
    names = {r.name for r in fig.renderers}
    assert {"boundary_pd", "boundary_sn", "boundary_grazing"} <= names
    src = e.research.overlay.sources
    pd_lines = src["period-doubling"].data["xs"]
    assert len(pd_lines) >= 2 and len(src["grazing"].data["xs"]) >= 1
    legend = e.research.boundary_status.object
    assert "period-doubling — " in legend and "curves from" in legend
    # the drawn period-doubling curves are those computed, and have the multiplier -1
    # there (the simulator's n-period map from the curve's orbit state)
    curves = [b for b in e.research.overlay.curves.curves if b.kind == "period-doubling"]
    assert [len(xs) for xs in pd_lines] == [len(b.values) for b in curves if len(b.values) > 1]
    for b in curves:
        for k in np.linspace(0, len(b.values) - 1, 5).astype(int)[1:-1]:
            p = b.params.replace(omega=b.values[k, 0], r=b.values[k, 1])
            mu = fd_multipliers(p, b.x[k], b.v[k], b.n)
            assert np.min(np.abs(mu + 1)) < 1e-6, (b.values[k], mu)
    # a setting of the map changes: the curves go, the job is cancelled
    generation = e.research.boundary_job.generation
    e.settings.c = 0.06
    assert e.research.boundary_job.generation > generation
    assert all(len(s.data["xs"]) == 0 for s in src.values())
    assert e.research.boundary_status.object == ""


def test_switch_off_clears_and_on_again_uses_the_shared_result(make_explorer, few_seeds):
    e = make_explorer(map_n="8", boundaries="1")
    e.research.compute(MAP)
    assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(120)
    drawn = len(e.research.overlay.sources["period-doubling"].data["xs"])
    e.settings.boundaries = False
    assert all(len(s.data["xs"]) == 0 for s in e.research.overlay.sources.values())
    e.settings.boundaries = True
    assert e.research.boundary_job.done.wait(30)
    assert len(e.research.overlay.sources["period-doubling"].data["xs"]) == drawn
    assert "stopped" not in e.research.boundary_status.object


def test_curves_download_as_csv_with_the_header(make_explorer, few_seeds):
    import io

    import pandas as pd

    from app.downloads import read_header
    e = make_explorer(map_n="8", boundaries="1")
    e.research.compute(MAP)
    assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(120)
    text = e.downloads.boundaries_csv(e.research.overlay,
                                      e.research.views[MAP].request).getvalue()
    head = read_header(text)
    assert (head["map_x"], head["map_y"]) == ("omega", "r") and head["c"] == "0.05"
    curves = e.research.overlay.curves.curves
    assert head["curve 0"].startswith(f"{curves[0].kind} of the {curves[0].orbit} orbit")
    df = pd.read_csv(io.StringIO(text), comment="#")
    for i, b in enumerate(curves):
        rows = df[df["curve"] == i]
        np.testing.assert_allclose(rows["omega"], b.values[:, 0], rtol=1e-9)
        np.testing.assert_allclose(rows["r"], b.values[:, 1], rtol=1e-9, atol=1e-12)


def test_the_diagram_marks_the_events_the_curves_start_from(make_explorer):
    """At the map's y value (r = 0.8) every curve starts on an event of a branch in x;
    the diagram's branch overlay (seeded also where the overlay seeds) marks the same
    event, and a one-parameter continuation at r = 0.8 started off it locates it too,
    each within 1e-8 in omega. With the overlay's six seeds: the one at omega = 2.9
    settles on an orbit (9 impacts in 4 periods) that the diagram's own seeds miss."""
    from app import branches
    e = _explorer_with_map_and_curves(make_explorer, "8")
    shown = e.branches.shown
    assert shown is not None and shown.complete, shown
    marked = {(ev.kind, ev.value) for ev in shown.events}
    # the markers drawn are those events (a marker per impact velocity; grazing past
    # an impact at positive speed is not drawn)
    assert set(e.branches.events.data["x"]) <= {v for _, v in marked}
    curves = e.research.overlay.curves.curves
    run = e.run
    checked = 0
    for b in curves:
        w, r = b.values[0]
        assert r == run.params.r
        if not run.bif_min < w < run.bif_max:
            continue
        near = [v for kind, v in marked if kind == b.kind and abs(v - w) < 1e-8]
        assert near, (b.kind, b.orbit, w)
        # il.continuation at r = 0.8 from the same orbit type just beside the event,
        # across it (a saddle-node has the orbit on one side only; where Newton finds
        # no such orbit beside it, as in the 9-impact cluster whose events lie within
        # 2e-5 of each other, the marker check above stands alone)
        for side in (-0.02, 0.02, -1e-3, 1e-3):
            p = b.params.replace(omega=w + side)
            orb = il.periodic_orbit(p, b.n, x0=b.x[0], v0=b.v[0])
            if orb.converged and orb.impacts == b.impacts:
                break
        else:
            continue
        br = il.continuation(p, "omega", w - side, n=b.n, x0=orb.x, v0=orb.v,
                             max_points=400)
        found = [ev.value for ev in br.events if ev.kind == b.kind]
        assert any(abs(v - w) < 1e-8 for v in found), (b.kind, b.orbit, w, found)
        checked += 1
    assert checked >= 3, checked
    branches.CACHE.clear()
    boundaries.CACHE.clear()


def _explorer_with_map_and_curves(make_explorer, map_n: str):
    """A fresh explorer from ``make_explorer`` (no cached branches or curves) whose
    diagram branches, regime map of ``map_n`` cells per side and boundary overlay are
    done."""
    from app import branches
    branches.CACHE.clear()
    boundaries.CACHE.clear()
    e = make_explorer(map_n=map_n, boundaries="1", branches="1")
    assert e.diagram.branch_job.done.wait(300)
    e.research.compute(MAP)
    assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(300)
    return e


def _located(b, k) -> list:
    """The events of ``b``'s kind that one-parameter continuations in omega at the y value
    of the curve's point ``k`` locate, each started just beside the point on the curve's
    orbit type (found from the point's state by il.periodic_orbit) and run across it. On
    the side of a grazing where the touch is an impact the orbit has one impact more."""
    w, r = b.values[k]
    counts = (b.impacts, b.impacts + 1) if b.kind == "grazing" else (b.impacts,)
    found = []
    for side in (-1e-3, 1e-3, -0.02, 0.02):
        p = b.params.replace(omega=w + side, r=r)
        orb = il.periodic_orbit(p, b.n, x0=b.x[k], v0=b.v[k])
        if not orb.converged or orb.impacts not in counts:
            continue
        br = il.continuation(p, "omega", w - side, n=b.n, x0=orb.x, v0=orb.v,
                             max_points=400)
        found += [ev.value for ev in br.events if ev.kind == b.kind]
    return found


def test_curves_of_a_region_off_the_current_line_are_drawn(make_explorer, few_seeds):
    """With the map's periodic cells as seeds the overlay holds curves that never cross
    the current line r = 0.8 (islands below or above it), which the branches at r = 0.8
    cannot start. Reference: at the y value of a point inside such a curve, a
    one-parameter continuation in omega (il.continuation, started off the curve on the
    same orbit type, either side, and run across it) locates the same event within 1e-8
    in omega."""
    e = make_explorer(map_n="20", boundaries="1")
    e.research.compute(MAP)
    assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(300)
    shown = e.research.overlay.curves
    assert shown.complete and not shown.waiting, shown.message
    assert "regions of the map" in e.research.boundary_status.object
    # both halves of a curve start on the same event: the curve is their union
    whole: dict = {}
    for b in shown.curves:
        whole.setdefault((b.kind, b.orbit, tuple(b.values[0])), []).append(b)
    off = [halves for halves in whole.values()
           if not any(h.values[:, 1].min() <= 0.8 <= h.values[:, 1].max() for h in halves)]
    assert off, "no curve off the line r = 0.8"
    checked = 0
    for halves in off:
        b = max(halves, key=lambda h: len(h.values))
        if len(b.values) < 5:
            continue
        k = len(b.values) // 2
        found = _located(b, k)
        assert any(abs(v - b.values[k, 0]) < 1e-8 for v in found), (b.kind, b.orbit,
                                                                     b.values[k], found)
        checked += 1
    assert checked >= 2, checked


def test_an_event_on_a_drawn_curve_is_not_followed_again(few_seeds):
    """The period-doubling curve of the 1-impact period-1 orbit bends: at r = 0.8 the
    branch in omega meets it twice (both period-doublings located independently by
    il.continuation). The overlay draws it once, from one of the two, and it passes the
    other within 1e-3 of the box."""
    from app import map_seeds
    run = state.validate(state.defaults())
    sets = list(boundaries.compute(boundaries.BoundaryRequest(run, "omega", "r")))
    pd1 = [b for b in sets[-1].curves
           if b.kind == "period-doubling" and b.orbit == "1-impact period-1"
           and 1.0 < b.values[0, 0] < 1.3]
    starts = {b.values[0, 0] for b in pd1}
    assert len(starts) == 1 and len(pd1) == 2, [b.values[0] for b in pd1]
    br = il.continuation(run.params.replace(omega=1.6), "omega", 0.9)
    both = [ev.value for ev in br.events if ev.kind == "period-doubling"]
    assert len(both) == 2 and min(abs(v - w) for v in both for w in starts) < 1e-8, both
    other = next(v for v in both if min(abs(v - w) for w in starts) > 1e-3)
    pts = np.concatenate([b.values for b in pd1]) / np.array([4.9, 1.0])
    p = np.array([other, 0.8]) / np.array([4.9, 1.0])
    seg_a, seg_b = pts[:-1], pts[1:]
    d = seg_b - seg_a
    t = np.clip(np.sum((p - seg_a) * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300),
                0, 1)
    assert np.min(np.hypot(*(seg_a + t[:, None] * d - p).T)) < 1e-3
    assert map_seeds.SAME_POINT >= 1e-3


def test_the_diagram_marks_every_crossing_of_the_curves(make_explorer, monkeypatch):
    """Each boundary curve crosses the line r = 0.8 where a branch of the diagram's
    overlay there (il.continuation in omega at r = 0.8, independent of il.boundary) has an
    event of the curve's kind: the crossings where curves start, a bent curve's second
    crossing (the 9-impact period-4 grazing curve turns back across the line) and those
    of curves seeded from the map's regions. The diagram's event lies on the crossing
    segment of the curve's polyline (within 1e-6), and within 1e-3 of the linear
    interpolation there (the polyline's chord error)."""
    import math

    from app import branches
    monkeypatch.setattr(branches, "WALL_TIME", math.inf)    # complete on a loaded machine
    e = _explorer_with_map_and_curves(make_explorer, "20")
    assert e.research.overlay.curves.complete, e.research.overlay.curves.message
    assert e.diagram.branch_job.done.wait(600)
    shown = e.branches.shown
    assert shown is not None and shown.complete, shown
    run = e.run
    y = run.params.r
    crossings = starts = 0
    for b in e.research.overlay.curves.curves:
        w, r = b.values[:, 0], b.values[:, 1]
        for i in np.flatnonzero((r[:-1] - y) * (r[1:] - y) <= 0):
            f = 0.0 if r[i + 1] == r[i] else (y - r[i]) / (r[i + 1] - r[i])
            xc = w[i] + f * (w[i + 1] - w[i])
            if not run.bif_min + 1e-3 < xc < run.bif_max - 1e-3:
                continue
            lo, hi = sorted((w[i], w[i + 1]))
            near = [ev.value for ev in shown.events if ev.kind == b.kind
                    and lo - 1e-6 <= ev.value <= hi + 1e-6 and abs(ev.value - xc) < 1e-3]
            assert near, (b.kind, b.orbit, xc, b.values[i:i + 2])
            crossings += 1
            starts += i == 0 and r[0] == y
    assert crossings - starts >= 3, (crossings, starts)
    branches.CACHE.clear()
    boundaries.CACHE.clear()


def test_curves_asked_before_the_map_is_done_come_again_with_its_regions(few_seeds):
    """The overlay never waits for the map: asked while the map runs it ends with the
    branches' curves and says it is waiting; asked again once the cells are there it
    starts from those curves (kept for all sessions) and adds the regions' curves, the
    first ones unchanged; a map that will not finish ends it without the regions."""
    from app import map_seeds, research
    run = state.validate({**state.defaults(), "map_n": 16})
    mreq = research.map_request(run)
    cells = map_seeds.MapCells(mreq.key())
    req = boundaries.BoundaryRequest(run, run.map_x, run.map_y, cells)
    early = list(boundaries.compute(req))[-1]
    assert early.waiting and not early.complete and early.curves
    assert all(b.values[0, 1] == run.params.r for b in early.curves)
    blocks = list(research.map_rows(mreq, wall_time=float("inf")))
    cells.fill(mreq.values_x, mreq.values_y, np.concatenate([b.impacts for b in blocks]),
               np.concatenate([b.period for b in blocks]))
    sets = list(boundaries.compute(req))
    assert sets[0].curves == early.curves and not sets[0].complete
    final = sets[-1]
    assert final.complete and not final.waiting and "regions of the map" in final.message
    assert final.curves[:len(early.curves)] == early.curves
    assert len(final.curves) > len(early.curves)
    lost = map_seeds.MapCells(("another map",))
    lost.give_up()
    gone = list(boundaries.compute(boundaries.BoundaryRequest(run, run.map_x, run.map_y,
                                                              lost)))[-1]
    assert not gone.complete and not gone.waiting and "did not finish" in gone.message
