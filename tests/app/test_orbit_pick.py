"""Click an orbit without a browser: a tap on a branch of the diagram's overlay, or on a
boundary curve of the regime map, starts the scene on that orbit.

Reference: the orbit's fixed point solved independently, by scipy.optimize on the
simulator's n-period map (``il.simulate`` from a state at t = 0 to t = nT), from a
rough start; never the app's or the continuation's numbers."""
import types

import numpy as np
import pytest
from scipy.optimize import fsolve

import impactlib as il
from app import orbit_pick, research, state
from app.boundaries import BoundarySet
from app.research_panel import MAP

#: r = 0.6 (Fig. 3d): the period-1 orbit loses stability at omega ~ 2.67 (a period
#: doubling), so at omega = 3 it is unstable, multipliers about -4 and -0.07.
DIAGRAM = {"r": "0.6", "branches": "1", "bif_min": "1.5", "bif_max": "3.5", "bif_n": "40"}


def period_map(p, n, z):
    sol = il.simulate(p, t_end=n * p.T, t_record=n * p.T, x0=z[0], v0=z[1])
    return np.array(sol.final[1:3])


def fixed_point(p, n, guess):
    """The fixed point of the n-period map near ``guess`` (scipy's hybrid method)."""
    z, info, ok, msg = fsolve(lambda z: period_map(p, n, z) - z, guess, xtol=1e-13,
                              full_output=True)
    assert ok == 1, msg
    return z


def tap(x, y):
    return types.SimpleNamespace(x=x, y=y)


def unstable_period_one(e, value):
    """(branch, index) of the unstable period-1 branch's point nearest ``value``."""
    for b in e.branches.shown.branches:
        if b.n == 1 and b.impacts == 1:
            i = int(np.argmin(np.abs(b.param - value)))
            if abs(b.param[i] - value) < 0.05 and not b.stable[i]:
                return b, i
    raise AssertionError("no unstable period-1 branch point near omega = 3")


def test_a_tap_on_an_unstable_branch_starts_the_scene_on_its_orbit(make_explorer):
    e = make_explorer(**DIAGRAM)
    assert e.diagram.branch_job.done.wait(300)
    b, i = unstable_period_one(e, 3.0)
    diagram_generation = e.diagram.job.generation
    # a tap a few pixels beside the dashed line at omega ~ 3
    e.bifurcation._on_tap(tap(b.param[i] + 0.004, b.impact_velocities[i, 0] + 0.01))
    run = e.run
    p = run.params
    assert p.omega == pytest.approx(3.0, abs=0.005) and p.r == 0.6
    assert run.orbit_x0 is not None and run.scene_start[2] == 0.0
    # independent fixed point of the one-period map, from a rough start
    z = fixed_point(p, 1, [round(run.orbit_x0, 1), round(run.orbit_v0, 1)])
    scale = max(1.0, *np.abs(z))
    # the scene starts there, and its first period's section state is still there:
    # URL digits (1e-10 relative) times |mu| ~ 4 per period, fsolve's 1e-13: 1e-8
    assert abs(run.orbit_x0 - z[0]) < 1e-9 * scale and abs(run.orbit_v0 - z[1]) < 1e-9 * scale
    sec = e.section
    assert sec["t"][0] == 0.0 and sec["t"][1] == pytest.approx(p.T, rel=1e-12)
    assert abs(sec["x"][1] - z[0]) < 1e-8 * scale and abs(sec["v"][1] - z[1]) < 1e-8 * scale
    assert e.scene.trajectory["t"][0] == 0.0          # no transient discarded
    # x(t) opens on the run's first periods (the orbit followed, then left)
    rng = e.displacement.figure.x_range
    assert rng.start == 0.0 and rng.end == pytest.approx(24 * p.T, rel=1e-12)
    # unstable: the run leaves the orbit, and the caption says after how long, as the
    # map iterated from the scene's start departs by more than the stated tolerance
    z0, k = np.array([run.orbit_x0, run.orbit_v0]), 0
    while np.hypot(*(z0 - z)) <= orbit_pick.LEAVE_RTOL * scale:
        z0, k = period_map(p, 1, z0), k + 1
    text = e.caption.object
    assert "Unstable 1-impact period-1 orbit at ω = 3" in text, text
    assert f"left after ≈ {k} periods" in text, (k, text)
    assert 5 < k < 40          # |mu| ~ 4 from 1e-11: about 13 periods
    # the diagram and its branches stay; the link holds the orbit and gives it back
    assert e.diagram.job.generation == diagram_generation
    assert e.branches.shown is not None and len(e.branches.unstable.data["xs"]) > 0
    q = state.to_query(run)
    assert {"orbit_x0", "orbit_v0"} <= set(q) and "t_record" in q and q["t_record"] == "250.0"
    values, scene, errors = state.from_query(q)
    assert not errors and state.validate(values) == run


def test_moving_a_parameter_leaves_the_orbit_and_a_tap_off_the_branches_moves_omega(
        make_explorer):
    e = make_explorer(**DIAGRAM)
    assert e.diagram.branch_job.done.wait(300)
    b, i = unstable_period_one(e, 3.0)
    e.bifurcation._on_tap(tap(b.param[i], b.impact_velocities[i, 0]))
    assert e.run.orbit_x0 is not None
    # a stable orbit (omega = 2, the paper's Fig. 2) is kept for the whole run: the
    # section points at t = kT, k = 1 .. floor(500 / T)
    b2 = next(b for b in e.branches.shown.branches if b.n == 1 and b.impacts == 1
              and b.param.min() < 2.0 < b.param.max())
    i = int(np.argmin(np.abs(b2.param - 2.0)))
    assert b2.stable[i]
    e.bifurcation._on_tap(tap(b2.param[i], b2.impact_velocities[i, 0]))
    assert e.run.params.omega == pytest.approx(2.0, abs=0.015) and e.run.orbit_x0 is not None
    periods = int(e.run.t_end // e.run.params.T)
    assert f"Stable 1-impact period-1 orbit at ω = {e.run.params.omega:g}" in e.caption.object
    assert f"kept for all {periods} periods" in e.caption.object, e.caption.object
    e.settings.omega = 2.5
    assert e.run.orbit_x0 is None and e.run.orbit_v0 is None
    assert e.run.scene_start == (None, 0.0, 250.0)
    assert "orbit at" not in e.caption.object
    # far from every branch line (impact velocity +0.5: none is above the wall)
    e.bifurcation._on_tap(tap(2.2, 0.5))
    assert e.run.params.omega == 2.2 and e.run.orbit_x0 is None


def test_a_link_to_an_orbit_is_checked(make_explorer):
    e = make_explorer(orbit_x0="0.5")                  # without its velocity
    assert "orbit_v0" in e.message and e.run.orbit_x0 is None
    e = make_explorer(orbit_x0="-0.5", orbit_v0="0")   # below the wall g = 0
    assert "orbit_x0" in e.message and e.run.orbit_x0 is None
    # a start that is no orbit: the scene starts there, the caption names no orbit
    e = make_explorer(orbit_x0="0.5", orbit_v0="0")
    assert e.run.scene_start == (0.5, 0.0, 0.0) and "orbit at" not in e.caption.object


def test_a_tap_on_a_period_doubling_curve_starts_the_scene_on_its_orbit(make_explorer):
    """The period-doubling curve of the period-1 orbit, from the branch at r = 0.6,
    drawn over the map: a tap on it starts the scene on the period-1 orbit at the tapped
    point (on the settings' grid), whose multiplier there is near -1."""
    e = make_explorer(**DIAGRAM)
    assert e.diagram.branch_job.done.wait(300)
    event = next(ev for b in e.branches.shown.branches if b.n == 1 for ev in b.events
                 if ev.kind == "period-doubling")
    curve = il.boundary(event, "r", 0.9, ds=0.01, max_points=200)
    assert len(curve.values) > 10
    e.research.build()
    view = e.research.views[MAP]
    view.started(research.map_request(e.run))
    e.research.overlay.show(BoundarySet((curve,), 1, 1, True, "1 curve"))
    k = len(curve.values) // 2
    w, r = curve.values[k]
    view._on_tap(tap(w + 0.01, r))
    run = e.run
    p = run.params
    assert abs(p.omega - w) < 0.006 and abs(p.r - r) < 0.006
    z = fixed_point(p, 1, [round(run.orbit_x0, 1), round(run.orbit_v0, 1)])
    assert np.max(np.abs(z - [run.orbit_x0, run.orbit_v0])) < 1e-9 * max(1.0, *np.abs(z))
    # next to the curve (the grid moves the point less than 0.006 in each parameter):
    # a multiplier of the one-period map (central differences) close to -1
    h = 1e-6
    J = np.column_stack([(period_map(p, 1, z + d) - period_map(p, 1, z - d)) / (2 * h)
                         for d in (np.array([h, 0.0]), np.array([0.0, h]))])
    assert np.min(np.abs(np.linalg.eigvals(J) + 1)) < 0.1
    assert "1-impact period-1 orbit at ω" in e.caption.object
    # the map and its curves stay valid: the scene alone starts on the orbit
    assert research.map_request(run).key() == view.request.key()
    assert e.research.overlay.curves is not None
