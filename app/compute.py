"""Scene computations shared by all sessions: cached simulations and screen budgets.

Only immutable results are shared: ``pn.cache`` keyed by the frozen ``il.Params`` plus
the run options, bounded (LRU). Everything here is plain numpy; no widgets.
"""
from __future__ import annotations

import dataclasses
import functools
import math
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
#: Ceilings of one scene simulation: reaching one stops the run with
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


#: The time plot opens on the last FIRST_PERIODS forcing periods of the window. The
#: scene's run samples that window for a plot up to FIRST_PIXELS wide as well (besides
#: its SCENE_POINTS even samples), so the plot's first window needs no run of its own.
#: A scene view is 233-467 px wide in the layouts measured (docs/guide/teaching.md), and
#: 1000 is the width the plot assumes before it is first drawn.
FIRST_PERIODS = 8
FIRST_PIXELS = 1000


def first_window(run: Run) -> tuple[float, float]:
    """[start, end] of the time plot when a scene is first shown."""
    return max(run.scene_start[2], run.t_end - FIRST_PERIODS * run.params.T), run.t_end


def window_samples(period: float, start: float, end: float, pixels: int) -> int:
    """Samples the time plot needs on [start, end] for a plot ``pixels`` wide."""
    return int(max(SAMPLES_PER_PERIOD * (end - start) / period, 2 * pixels))


@dataclasses.dataclass(frozen=True)
class SceneGrid:
    """The dense sample times of a scene run: the even grid of SCENE_POINTS samples up to
    the time plot's first window, then the window's finer even grid. The scene views
    take every ``stride``-th window sample (as dense as the even grid), the time plot
    takes the window's (thinned to its width)."""

    times: np.ndarray
    first: int        # samples before the window
    stride: int


def scene_grid(key: tuple) -> SceneGrid:
    """The :class:`SceneGrid` of the scene run of ``key`` (Run.scene_key())."""
    options = dict(key[1:])
    return _scene_grid(float(options["t_record"]), float(options["t_end"]), key[0].T)


@functools.lru_cache(maxsize=64)
def _scene_grid(t_record: float, t_end: float, period: float) -> SceneGrid:
    start = max(t_record, t_end - FIRST_PERIODS * period)
    even = np.linspace(t_record, t_end, SCENE_POINTS)
    spacing = (t_end - t_record) / (SCENE_POINTS - 1)
    n = window_samples(period, start, t_end, FIRST_PIXELS)
    stride = 1
    if t_end > start:           # (the app's settings keep t_record < t_end)
        n = max(n, math.ceil((t_end - start) / spacing) + 1)
        stride = max(1, int((n - 1) * spacing / (t_end - start)))
    times = np.concatenate([even[even < start], np.linspace(start, t_end, n)])
    times.flags.writeable = False       # shared by every caller of the cache
    return SceneGrid(times, int(np.count_nonzero(even < start)), stride)


def scene_samples(sol: il.Solution, grid: SceneGrid) -> tuple:
    """(t, x, v) of the scene views from the scene run ``sol`` on ``grid``."""
    d, k, s = sol.dense, grid.first, grid.stride
    last = d.t.size - 1
    tail = [last] if last >= k and (last - k) % s else []
    return tuple(np.concatenate([a[:k], a[k::s], a[tail]]) for a in (d.t, d.x, d.v))


def window_samples_of(sol: il.Solution, grid: SceneGrid, need: int) -> tuple:
    """(t, x, v) of the time plot's first window from the scene run ``sol`` on ``grid``:
    its window samples, every s-th so that at least ``need`` remain."""
    d, k = sol.dense, grid.first
    n = d.t.size - k
    s = max(1, (n - 1) // max(need - 1, 1))
    tail = [d.t.size - 1] if n > 0 and (n - 1) % s else []
    return tuple(np.concatenate([a[k::s], a[tail]]) for a in (d.t, d.x, d.v))


@pn.cache(max_items=32, policy="LRU", hash_funcs=_HASH)
def _simulate(key: tuple, scene: bool, phase: float) -> il.Solution:
    params, options = key[0], dict(key[1:])
    return il.simulate(params, dense=scene_grid(key).times if scene else 0, phase=phase,
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


def simulate(key: tuple, scene: bool, phase: float) -> il.Solution:
    """``il.simulate`` for ``Run.scene_key()`` (Params, then (keyword, value) pairs) with
    the Poincare section at ``phase``, and the scene's dense samples (:func:`scene_grid`)
    if ``scene``; cached across sessions. Callers asking for the same run at once (the
    scene, stability and window jobs of one move) wait for one simulation instead of
    running three."""
    return once_at_a_time(("run", repr(key), scene, phase), lambda: _simulate(key, scene, phase))


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
    return simulate(run.scene_key(), True, section_phase(run))


def section_solution(run: Run) -> il.Solution:
    """The same run sampled at another Poincare section psi: an impacts-only simulation
    (no dense output), so a psi change alone never recomputes the trajectory."""
    return simulate(run.scene_key(), False, section_phase(run))


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


def trajectory_columns(sol: il.Solution, r: float, g: float, samples=None,
                       span=(-np.inf, np.inf)) -> dict:
    """Dense samples ((t, x, v), default all of ``sol``'s) merged with the impacts in
    ``span``: at each impact time the line passes through (g, v-) and (g, -r v-), so
    corners and velocity jumps are drawn exactly."""
    d = sol.dense
    t, x, v = (d.t, d.x, d.v) if samples is None else samples
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    v = np.asarray(v, dtype=float)
    ti = np.asarray(sol.impacts.t, dtype=float)
    vi = np.asarray(sol.impacts.v, dtype=float)
    if span[0] > -np.inf or span[1] < np.inf:
        inside = (ti >= span[0]) & (ti <= span[1])
        ti, vi = ti[inside], vi[inside]
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
    if (a, b) == first_window(run) and pixels <= FIRST_PIXELS:
        return first_window_columns(run, pixels)
    n = window_samples(p.T, a, b, pixels)
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


def first_window_columns(run: Run, pixels: int) -> dict:
    """The time plot's first window from the scene's own run (its samples there, thinned
    evenly to what a plot ``pixels`` wide needs, and its impacts there as corners)."""
    sol = scene_solution(run)
    a, b = first_window(run)
    samples = window_samples_of(sol, scene_grid(run.scene_key()),
                                window_samples(run.params.T, a, b, pixels))
    return trajectory_columns(sol, run.params.r, run.params.g, samples, (a, b))


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
    samples = scene_samples(sol, scene_grid(run.scene_key()))
    return SceneData(run=run, trajectory=trajectory_columns(sol, p.r, p.g, samples),
                     impacts=impacts,
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
