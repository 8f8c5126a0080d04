"""Scene computations shared by all sessions: cached simulations and screen budgets.

Only immutable results are shared: ``pn.cache`` keyed by the frozen ``il.Params`` plus
the run options, bounded (LRU). Everything here is plain numpy; no widgets.
"""
from __future__ import annotations

import dataclasses
import threading
import weakref

import numpy as np
import panel as pn

import impactlib as il
from impactlib.analysis.classify import classify_measured

from .state import Run

#: Evenly spaced samples of x(t), v(t) per time series (impact corners are added).
SCENE_POINTS = 4000
#: At most this many impact corners are inserted into the time series.
MAX_CORNERS = 2000
#: At most this many sticking intervals are shaded (the last ones).
MAX_STICKING = 2000
#: At most this many points in the impact map and the Poincare map.
MAX_MAP_POINTS = 20_000
#: Ceilings of one scene simulation (a scene is two): reaching one stops the run with
#: partial results and a message on the badge. Measured worst costs on this 2-core
#: machine: ~1.5 us per exact step (heavily damped), ~9 us per impact, ~0.05 us per rk4
#: step, so each simulation stays under ~0.4 s. The paper's scenes need <= 11k exact
#: steps and <= 2.3k impacts over 500 s.
SCENE_MAX_IMPACTS = 25_000
SCENE_MAX_STEPS = {"exact": 250_000, "rk4": 5_000_000, "rk45": 1_000_000}
SCENE_MAX_SAMPLES = 250_000

#: Cache keys here are tuples of Params and plain numbers, whose repr is exact and
#: stable: hashing it is one call, where pn.cache's own walk through the tuple
#: (panel 1.9.4) took about half the server CPU of an omega move (bench/bench_move.py).
KEY_HASH = {il.Params: lambda p: repr(p).encode(), "builtins.tuple": lambda t: repr(t).encode()}
_HASH = KEY_HASH


def scene_limits(method: str) -> il.RunLimits:
    """Work ceilings of one scene simulation with ``method``."""
    return il.RunLimits(max_impacts=SCENE_MAX_IMPACTS, max_steps=SCENE_MAX_STEPS[method],
                        max_samples=SCENE_MAX_SAMPLES)


@pn.cache(max_items=32, policy="LRU", hash_funcs=_HASH)
def _simulate(key: tuple, dense: int, phase: float) -> il.Solution:
    params, options = key[0], dict(key[1:])
    return il.simulate(params, dense=dense, phase=phase,
                       limits=scene_limits(options["method"]), **options)


_FLIGHTS_LOCK = threading.Lock()
_FLIGHTS: dict = {}


def once_at_a_time(key, fn):
    """fn() with callers of the same ``key`` taking turns, so that a second caller finds
    the first one's result in its cache instead of computing it again."""
    with _FLIGHTS_LOCK:
        lock, users = _FLIGHTS.get(key, (None, 0))
        lock = lock or threading.Lock()
        _FLIGHTS[key] = (lock, users + 1)
    try:
        with lock:
            return fn()
    finally:
        with _FLIGHTS_LOCK:
            lock, users = _FLIGHTS[key]
            if users == 1:
                del _FLIGHTS[key]
            else:
                _FLIGHTS[key] = (lock, users - 1)


def simulate(key: tuple, dense: int, phase: float) -> il.Solution:
    """``il.simulate`` for ``Run.scene_key()`` (Params, then (keyword, value) pairs);
    cached across sessions. Callers asking for the same run at once (the scene job and
    the stability job of one move) wait for one simulation instead of running two."""
    return once_at_a_time(("run", repr(key), dense, phase), lambda: _simulate(key, dense, phase))


_MEASURED: dict = {}


def classified(sol: il.Solution):
    """``classify_measured(sol)``: the motion and the Lyapunov measurement behind it (or
    None), once per Solution object (the scene's badge and the stability readout read
    the same one)."""
    def measure():
        hit = _MEASURED.get(id(sol))
        if hit is not None and hit[0]() is sol:
            return hit[1]
        got = classify_measured(sol)
        _MEASURED[id(sol)] = (weakref.ref(sol, lambda _, k=id(sol): _MEASURED.pop(k, None)), got)
        return got
    return once_at_a_time(("classify", id(sol)), measure)


def section_phase(run: Run) -> float:
    """The Poincare section psi of ``run``, inside [0, T]."""
    return min(max(run.psi, 0.0), run.params.T)


def scene_solution(run: Run) -> il.Solution:
    """The one run of a scene: dense samples for the four scene views and the Poincare
    section at psi in the same pass."""
    return simulate(run.scene_key(), SCENE_POINTS, section_phase(run))


def section_solution(run: Run) -> il.Solution:
    """The same run sampled at another Poincare section psi: an impacts-only simulation
    (no dense output), so a psi change alone never recomputes the trajectory."""
    return simulate(run.scene_key(), 0, section_phase(run))


@dataclasses.dataclass(frozen=True)
class SceneData:
    """Column data of the scene views, already within the screen budget."""

    run: Run
    trajectory: dict   # t, x, v (dense samples with exact impact corners)
    impacts: dict      # t, phase, v (before impact), v_after
    sticking: dict     # start, end of the intervals the mass rests on the wall
    label: str
    elapsed: float
    status: int
    message: str


def trajectory_columns(sol: il.Solution, r: float, g: float) -> dict:
    """Dense samples merged with the impacts: at each impact time the line passes through
    (g, v-) and (g, -r v-), so corners and velocity jumps are drawn exactly."""
    d = sol.dense
    t = np.asarray(d.t, dtype=float)
    x = np.asarray(d.x, dtype=float)
    v = np.asarray(d.v, dtype=float)
    ti = np.asarray(sol.impacts.t, dtype=float)
    vi = np.asarray(sol.impacts.v, dtype=float)
    if ti.size > MAX_CORNERS:
        keep = np.linspace(0, ti.size - 1, MAX_CORNERS).round().astype(int)
        ti, vi = ti[keep], vi[keep]
    if ti.size:
        tt = np.concatenate([t, ti, ti])
        xx = np.concatenate([x, np.full(ti.size, g), np.full(ti.size, g)])
        vv = np.concatenate([v, vi, -r * vi])
        rank = np.concatenate([np.ones(t.size), np.zeros(ti.size), np.full(ti.size, 2.0)])
        order = np.lexsort((rank, tt))
        t, x, v = tt[order], xx[order], vv[order]
    return {"t": t, "x": x, "v": v}


#: The time plot's samples for the window on screen: at least this many per forcing
#: period (a smooth curve, and a faithful animation), at least two per pixel column...
SAMPLES_PER_PERIOD = 48
#: ...and at most this many; a wider window is drawn as its envelope (the lowest and
#: highest x of each pixel column, from up to ENVELOPE_SAMPLES samples, under the
#: scene limit SCENE_MAX_SAMPLES).
MAX_WINDOW_SAMPLES = 24_000
ENVELOPE_SAMPLES = 240_000


def window_columns(run: Run, start: float, end: float, pixels: int) -> dict:
    """x(t), v(t) on screen for the window [start, end] (clipped to the recorded one):
    samples dense enough for the window and the screen, with the exact impact corners;
    or, when that would exceed MAX_WINDOW_SAMPLES, the envelope per pixel column
    (``v`` NaN: not a motion to animate). The run is the scene's own (same start, same
    steps: its impacts are bit for bit those of the scene), simulated up to ``end``.
    """
    p = run.params
    a, b = max(float(start), run.scene_start[2]), min(float(end), run.t_end)
    pixels = int(min(max(pixels or 1000, 200), 4000))
    if not b > a:
        return {"t": np.zeros(0), "x": np.zeros(0), "v": np.zeros(0)}
    n = int(max(SAMPLES_PER_PERIOD * (b - a) / p.T, 2 * pixels))
    options = {**dict(run.scene_key()[1:]), "t_end": b, "t_record": a}
    envelope = n > MAX_WINDOW_SAMPLES
    sol = il.simulate(p, dense=min(n, ENVELOPE_SAMPLES),
                      limits=scene_limits(options["method"]), **options)
    cols = trajectory_columns(sol, p.r, p.g)
    if not envelope:
        return cols
    t, x = cols["t"], cols["x"]
    edges = np.linspace(a, b, pixels + 1)
    col = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, pixels - 1)
    starts = np.flatnonzero(np.r_[True, col[1:] != col[:-1]])
    lo, hi = np.minimum.reduceat(x, starts), np.maximum.reduceat(x, starts)
    tc = 0.5 * (edges[col[starts]] + edges[col[starts] + 1])
    return {"t": np.repeat(tc, 2), "x": np.column_stack((lo, hi)).ravel(),
            "v": np.full(2 * tc.size, np.nan)}


def last(a, n: int) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return a[-n:] if a.size > n else a


def build_scene(run: Run) -> SceneData:
    """Compute (or fetch from the cache) the scene of ``run``. Raises ValueError for
    settings the core rejects."""
    sol = scene_solution(run)
    p = run.params
    imp = sol.impacts
    v = last(imp.v, MAX_MAP_POINTS)
    impacts = {"t": last(imp.t, MAX_MAP_POINTS), "phase": last(imp.phase, MAX_MAP_POINTS),
               "v": v, "v_after": -p.r * v}
    stick = np.asarray(sol.sticking, dtype=float).reshape(-1, 2)[-MAX_STICKING:]
    return SceneData(run=run, trajectory=trajectory_columns(sol, p.r, p.g), impacts=impacts,
                 sticking={"start": stick[:, 0].copy(), "end": stick[:, 1].copy()},
                 label=classified(sol)[0].label, elapsed=float(sol.elapsed),
                 status=int(sol.status), message=str(sol.message))


def section_columns(run: Run, sol: il.Solution | None = None) -> dict:
    """The Poincare section of ``run`` from ``sol`` (a run of it at its psi), or from an
    impacts-only run."""
    sol = section_solution(run) if sol is None else sol
    ps = sol.poincare
    return {"t": last(ps.t, MAX_MAP_POINTS), "x": last(ps.x, MAX_MAP_POINTS),
            "v": last(ps.v, MAX_MAP_POINTS)}


def scene_and_section(run: Run, shown) -> tuple | ValueError:
    """(scene, section) of ``run``, reusing what did not change since ``shown()`` (the
    run, scene and section on screen); a ValueError if the core refuses the settings."""
    prev, old_scene, section = shown()
    scene = old_scene
    try:
        if prev is None or run.scene_key() != prev.scene_key():
            # one run for both: the scene's trajectory and its section at psi
            scene = build_scene(run)
            section = section_columns(run, scene_solution(run))
        elif run.psi != prev.psi:
            section = section_columns(run)
    except ValueError as exc:
        return exc
    return scene, section
