"""Bounded cost: every computation has a ceiling on impacts, steps, output and time.

Wall-time bounds here are loose watchdogs (several times the target), not benchmarks:
they catch a missing ceiling (tens of seconds, a hang), not a slow machine.
"""
from __future__ import annotations

import math
import time

import numpy as np
import pytest

import impactlib as il

#: The app's ceilings per scene simulation.
SCENE = dict(max_steps=250_000, max_impacts=25_000)
#: Seconds after which a bounded computation counts as hung. A guard, not a speed claim:
#: the work ceilings bound these runs to well under a second on an idle 2-core machine
#: (speed is measured in bench/); the margin is for a machine shared with other jobs.
HANG = 10.0

EXTREME = {
    "omega=0.001": dict(omega=0.001),
    "k=1e6": dict(k=1e6),
    "m=1e-6": dict(m=1e-6),
    "r=0.99 chattering (omega=0.2)": dict(r=0.99, omega=0.2),
    "r=0.99, c=0 (omega=0.2)": dict(r=0.99, c=0.0, omega=0.2),
    "m=1e-6, k=1e6": dict(m=1e-6, k=1e6),
    "c=1e4 (overdamped)": dict(c=1e4),
    "k=1e12": dict(k=1e12),
}


def _sane(sol, t_end):
    """Status and message agree with what was computed; partial results are kept."""
    assert sol.status in (0, 1, 2, 3), sol.status
    for a in (sol.impacts.t, sol.impacts.v, sol.poincare.x, sol.poincare.v):
        assert np.all(np.isfinite(a))
    assert np.all(np.diff(sol.impacts.t) >= 0)
    assert np.all(sol.impacts.v <= 0)
    if sol.status == 0:
        assert sol.message == "reached t_end" and sol.final[0] == pytest.approx(t_end)
    elif sol.status in (1, 2):
        assert "limit" in sol.message and "stopped at t =" in sol.message, sol.message
        assert sol.final[0] < t_end
        if len(sol.impacts):
            assert sol.impacts.t[-1] <= sol.final[0] + 1e-9
    label = il.classify(sol).label
    assert label, label


@pytest.mark.timeout(120)
@pytest.mark.parametrize("t_end", [500.0, 20_000.0])
@pytest.mark.parametrize("name", list(EXTREME))
def test_extreme_physics_stays_responsive_under_the_scene_ceiling(name, t_end):
    p = il.Params(**EXTREME[name])
    il.simulate(il.Params(), t_end=10.0, t_record=5.0)            # JIT warm
    tic = time.perf_counter()
    sol = il.simulate(p, t_end=t_end, t_record=t_end / 2, dense=4000, **SCENE)
    elapsed = time.perf_counter() - tic
    _sane(sol, t_end)
    # a hang guard (the work ceilings bound it; speed itself is measured in bench/)
    assert elapsed < HANG, f"{name}: {elapsed:.2f} s for one run under the scene ceiling"


def test_omega_tiny_reports_an_undetermined_window():
    sol = il.simulate(il.Params(omega=0.001), t_end=500.0, t_record=250.0)
    assert sol.status == 0
    assert il.classify(sol).kind == "undetermined"       # window << one period


def test_the_ceiling_gives_partial_results_with_a_message():
    p = il.Params(omega=0.2, r=0.99)
    full = il.simulate(p, t_end=2000.0, t_record=0.0)
    part = il.simulate(p, t_end=2000.0, t_record=0.0, max_impacts=len(full.impacts) // 3)
    assert part.status == 1 and "impact limit" in part.message
    n = len(part.impacts)
    assert 0 < n <= len(full.impacts) // 3 + 1
    np.testing.assert_allclose(part.impacts.t, full.impacts.t[:n], rtol=0, atol=1e-9)
    part = il.simulate(p, t_end=2000.0, t_record=0.0, max_steps=full.nsteps // 3)
    assert part.status == 2 and "step limit" in part.message


def test_output_size_is_bounded_by_the_sample_limit():
    """A window holding more forcing periods than max_samples is refused up front with a
    message naming the window, instead of allocating it."""
    with pytest.raises(ValueError, match=r"t_end.*omega=1000"):
        il.simulate(il.Params(omega=1000.0), t_end=20_000.0, t_record=0.0,
                    limits=il.RunLimits(max_samples=250_000))


# -- the app's ceilings ------------------------------------------------------------------

WORST_URLS = {
    "c=1e4": {"c": "1e4"},
    "m=1e-12": {"m": "1e-12"},
    "k=1e12": {"k": "1e12"},
    "m=1e-6": {"m": "1e-6"},
    "rk4 dt=1e-6 over 20000 s": {"method": "rk4", "dt": "1e-6", "t_end": "20000"},
    "omega=1000 over 20000 s": {"omega": "1000", "t_end": "20000", "t_record": "0"},
    "rk45 rtol=1e-13 over 20000 s": {"method": "rk45", "rtol": "1e-13", "atol": "1e-15",
                                     "t_end": "20000"},
    "chattering r=0.99 over 20000 s": {"omega": "0.2", "r": "0.99", "t_end": "20000",
                                       "t_record": "0"},
}


def _needs_ceiling(module) -> None:
    """Until the app passes a work ceiling to the core (reliability_needs.md items 1-3)
    these tests would each block for up to a minute: mark them expected-to-fail at
    once instead. Once the ceiling is in, they run for real."""
    import inspect

    if "max_steps" not in inspect.getsource(module):
        pytest.xfail(f"reliability_needs.md items 1-3: {module.__name__} passes no "
                     "work ceiling to the core")


def _solution_bytes(sol) -> int:
    n = sol.sticking.nbytes
    for part in (sol.impacts, sol.poincare, sol.dense):
        if part is not None:
            n += sum(a.nbytes for a in vars(part).values() if isinstance(a, np.ndarray))
    return n


@pytest.mark.timeout(300)
@pytest.mark.parametrize("name", list(WORST_URLS))
def test_app_scene_has_a_work_ceiling(name):
    """One scene (trajectory + Poincare section) of the worst settings a URL or a typed
    value can ask for: well under a second (target 0.5 s), a bounded result, and a
    message on the badge when the ceiling cut it short."""
    from app import compute, state

    _needs_ceiling(compute)
    values, errors = state.parse_query(WORST_URLS[name])
    assert errors == []
    try:
        run = state.validate(values)
    except ValueError:
        return                      # refused up front with a message: also bounded
    compute.simulate.clear() if hasattr(compute.simulate, "clear") else None
    tic = time.perf_counter()
    try:
        scene = compute.build_scene(run)
        section = compute.section_columns(run)
    except ValueError as exc:       # refused by the core (e.g. the sample limit)
        assert time.perf_counter() - tic < HANG
        assert "t_end" in str(exc) or "omega" in str(exc)
        return
    elapsed = time.perf_counter() - tic
    assert elapsed < HANG, f"{name}: scene took {elapsed:.2f} s"
    for sol in (compute.scene_solution(run), compute.section_solution(run)):
        assert _solution_bytes(sol) < 16e6, f"{name}: {_solution_bytes(sol) / 1e6:.0f} MB"
    assert len(section["x"]) <= compute.MAX_MAP_POINTS
    if scene.status:
        assert "limit" in scene.message


@pytest.mark.timeout(300)
def test_app_diagram_has_a_work_ceiling():
    """A diagram chunk of the worst settings finishes in a bounded time."""
    from app import diagram, state

    _needs_ceiling(diagram)
    values, _ = state.parse_query({"c": "1e4", "bif_n": "400"})
    run = state.validate(values)
    chunk = diagram.chunk_values(diagram.sweep_values(run))[0][:16]
    tic = time.perf_counter()
    part = diagram.compute_chunk(run, chunk)
    elapsed = time.perf_counter() - tic
    assert elapsed < HANG, f"{elapsed:.1f} s for {chunk.size} values"
    assert part["partial"] >= 0


@pytest.mark.timeout(300)
def test_one_heavy_session_does_not_stall_another():
    """Session A types c = 1e4; session B, meanwhile, moves omega and still gets its
    scene within a couple of seconds (the server's event loop is never held long)."""
    from app import compute
    from rel_server import Served, open_session, pump, slider, source, value_input

    _needs_ceiling(compute)
    srv = Served("heavy.log")
    try:
        a = open_session(srv.url, {"bif_n": "24"})
        b = open_session(srv.url, {"bif_n": "24"})
        try:
            value_input(a.document, "c").value = 1e4
            pump(a, lambda: False, 0.3)                 # send it
            x = source(b.document, "displacement").data["x"]
            tic = time.monotonic()
            slider(b.document, "omega").value = 2.7
            ok = pump(b, lambda: source(b.document, "displacement").data["x"] is not x, 8)
            latency = time.monotonic() - tic
        finally:
            a.close()
            b.close()
    finally:
        srv.stop()
    assert ok and latency < 3.0, f"B waited {latency:.1f} s behind A's computation"


def test_rk4_step_beyond_stability_is_refused_not_run():
    with pytest.raises(ValueError, match="stability"):
        il.simulate(il.Params(k=1e6), method="rk4", dt=0.01)
    lim = il.rk4_stability_limit(il.Params(k=1e6))
    assert math.isfinite(lim) and lim < 0.01


def test_lightly_damped_exact_resonance_completes_like_the_undamped_one():
    """At omega = omega_n the particular solution's amplitude 1/(2 c omega) and the
    homogeneous part's energy are huge for c = 1e-10 and cancel in x; the search bounds
    x's derivatives by the motion's own energy as well (flight.derivative_bounds), so the
    run ends within a small step ceiling, with the impacts and final state of c = 0 (the
    exact resonance formula).  c changes the motion over 5 s by ~1e-10; the closed form's
    rounding at this c is eps / (2 c omega) ~ 1.1e-6 in x, hence 1e-6 (the chatter's
    accumulation time is well conditioned, test_reference).  Found by test_invariants'
    Hypothesis search (m = k = g = 0.35, omega = 1), where it ran to the 20M step ceiling."""
    run = dict(t_end=5.0, t_record=0.0, x0=0.35, v0=0.0,
               limits=il.RunLimits(max_steps=200_000))
    base = dict(m=0.35, k=0.35, g=0.35, r=0.0784, omega=1.0)
    ref = il.simulate(il.Params(c=0.0, **base), **run)
    assert ref.status == il.RunStatus.OK
    sol = il.simulate(il.Params(c=1e-10, **base), **run)
    assert sol.status == il.RunStatus.OK, sol.message
    np.testing.assert_allclose(sol.impacts.t, ref.impacts.t, rtol=0, atol=1e-6)
    np.testing.assert_allclose(sol.final[:3], ref.final[:3], rtol=0, atol=1e-6)
    assert sol.final[3] == ref.final[3]
