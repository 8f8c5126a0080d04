"""Click an orbit: a tap on a branch of the diagram's overlay, or on a boundary curve of
the regime map, starts the scene on that periodic orbit.

A tap picks the nearest point of a drawn branch or curve (within ``REACH`` of the
picture's span).  Its parameters are put on the settings' grid (as every value the app
computes with), and the orbit is solved there by ``il.periodic_orbit`` from that point's
state (Newton with the exact Jacobian; an unstable orbit is a fixed point like a stable
one).  The scene then starts on the orbit's state at t = 0, the section phase of the
branches, with no transient discarded: the settings ``orbit_x0``, ``orbit_v0`` say so,
in the URL like any other state.  They start the scene alone (``Run.scene_start``): the
diagram and the regime map, with the branches and curves tapped, keep their own start
and window and are not computed again.

The caption's words come from the settings alone (``recognise``), so a link gives the
same caption: the start must return to itself after n periods and lie on a periodic
orbit (Newton stays there); how long the run stays on it is measured on the run's own
section points at t = k T (the first one farther than ``LEAVE_RTOL`` from the orbit's).
Nothing here knows about Panel.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

import impactlib as il

from .settings import BY_NAME
from .state import rounded

#: A tap picks a point within this share of the picture's width and height (an ellipse).
REACH = 0.03
#: Newton from the picked point may move this far (relative to the orbit's size, at
#: least 1) and still be that orbit: the settings' grid moves the parameters a little.
SAME_ORBIT_RTOL = 0.05
#: A start that comes back within this (relative) after n periods is looked at as an
#: orbit; Newton must then stay within START_RTOL of it (the URL keeps 10 digits).
RETURN_RTOL = 1e-6
START_RTOL = 1e-7
#: The run has left the orbit once a section point lies this far (relative) from it.
LEAVE_RTOL = 1e-3
MAX_PERIOD = 8


@dataclass(frozen=True)
class Pick:
    """A tapped orbit: the settings that start the scene on it, and the orbit."""

    settings: dict
    orbit: object        # il.PeriodicOrbit at the settings' parameters


@dataclass(frozen=True)
class OrbitStart:
    """A run that starts on a periodic orbit: ``orbit`` (il.PeriodicOrbit at t = 0),
    ``close`` the forcing periods the run stays within ``LEAVE_RTOL`` of it and
    ``periods`` those the run has (``close == periods``: it never leaves)."""

    orbit: object
    close: int
    periods: int


def nearest(curves, x: float, y: float, x_span: float, y_span: float):
    """(curve, index) of the point of ``curves`` (pairs of equally long x, y arrays,
    with the curve they belong to: ``(xs, ys, curve)``) nearest to the tap (x, y) in
    units of the picture's spans, or None when none lies within ``REACH``."""
    best, found = 1.0, None
    for xs, ys, curve in curves:
        d = np.hypot((np.asarray(xs) - x) / (REACH * x_span),
                     (np.asarray(ys) - y) / (REACH * y_span))
        d = np.where(np.isfinite(d), d, np.inf)        # left-out points are never near
        if d.size and d.min() <= best:
            i = int(np.argmin(d))
            best, found = float(d[i]), (curve, i)
    return found


def branch_points(branches):
    """A branch set's tappable lines: each impact velocity of each branch, admissible
    points only (as drawn)."""
    out = []
    for b in branches:
        ok = b.admissible & np.all(b.impact_velocities <= 0.0, axis=1)
        for j in range(b.impact_velocities.shape[1]):
            out.append((np.where(ok, b.param, np.nan), b.impact_velocities[:, j], b))
    return out


def state_at_zero(p: il.Params, n: int, x: float, v: float, phase: float):
    """The orbit's state at t = 0 (mod nT) from its state (x, v) at t = phase."""
    if phase == 0.0:
        return x, v
    total = n * p.T
    sol = il.simulate(p, t_end=total, t_record=total, x0=x, v0=v, t0=phase)
    return float(sol.final[1]), float(sol.final[2])


def solve(p: il.Params, n: int, x: float, v: float):
    """The period-n orbit of ``p`` near (x, v) at t = 0, or None (Newton fails, or moves
    away to another orbit, or the orbit sticks to the wall)."""
    try:
        orb = il.periodic_orbit(p, n, x0=x, v0=v, phase=0.0)
    except ValueError:
        return None
    scale = max(1.0, abs(x), abs(v))
    if (not orb.converged or orb.sticks
            or max(abs(orb.x - x), abs(orb.v - v)) > SAME_ORBIT_RTOL * scale):
        return None
    return orb


def on_grid(name: str, value: float) -> list[float]:
    """Values of setting ``name`` on its grid next to ``value``, nearest first (where
    the nearest one misses the orbit, past a fold, the next may hold it)."""
    s = BY_NAME[name]
    near = rounded(s, value)
    if s.step is None:
        return [near]
    out = {near}
    for k in (-1, 1):
        try:
            q = rounded(s, near + k * s.step)
        except (TypeError, ValueError):
            continue
        out.add(q)
    return sorted(out, key=lambda q: abs(q - value))


def pick(p: il.Params, values: dict, n: int, x: float, v: float, phase: float) -> Pick | None:
    """The settings that start the scene on the period-n orbit through (x, v) at
    t = phase of ``p`` with ``values`` (parameter -> value) put on the settings' grid
    (the nearest grid point where Newton finds that orbit)."""
    try:
        x, v = state_at_zero(p.replace(**values), n, x, v, phase)
    except ValueError:
        return None
    grids = [[]]
    for name, value in values.items():
        grids = [g + [(name, q)] for g in grids for q in on_grid(name, float(value))]
    grids.sort(key=lambda g: sum(((q - values[n_]) / (BY_NAME[n_].step or 1.0)) ** 2
                                 for n_, q in g))
    for grid in map(dict, grids):
        try:
            q = p.replace(**grid)
        except ValueError:
            continue
        orb = solve(q, n, x, v)
        if orb is not None and orb.x >= q.g:
            settings = {**grid, "orbit_x0": rounded(BY_NAME["orbit_x0"], orb.x),
                        "orbit_v0": rounded(BY_NAME["orbit_v0"], orb.v)}
            return Pick(settings, orb)
    return None


def pick_on_branch(branches, x: float, y: float, x_span: float, y_span: float) -> Pick | None:
    """The orbit of the branch point nearest to a tap at (x, y) of the diagram."""
    hit = nearest(branch_points(branches), x, y, x_span, y_span)
    if hit is None:
        return None
    b, i = hit
    return pick(b.start.params, {b.name: b.param[i]}, b.n, b.x[i], b.v[i], b.phase)


def pick_on_curve(curves, x: float, y: float, x_span: float, y_span: float) -> Pick | None:
    """The orbit of the boundary-curve point nearest to a tap at (x, y) of the map."""
    hit = nearest([(b.values[:, 0], b.values[:, 1], b) for b in curves if len(b.values)],
                  x, y, x_span, y_span)
    if hit is None:
        return None
    b, i = hit
    return pick(b.params, dict(zip(b.names, b.values[i])), b.n, b.x[i], b.v[i], b.phase)


def recognise_key(run) -> tuple | None:
    """What ``recognise(run)`` depends on; None for a scene not started on an orbit."""
    if run is None or run.orbit_x0 is None:
        return None
    return (run.params, run.orbit_x0, run.orbit_v0, run.t_end)


def recognise(run) -> OrbitStart | None:
    """The periodic orbit ``run``'s scene starts on (see the module's note); None when
    it starts on none."""
    key = recognise_key(run)
    return None if key is None else _recognise(*key)


@functools.lru_cache(maxsize=64)
def _recognise(p: il.Params, x0: float, v0: float, t_end: float) -> OrbitStart | None:
    try:
        sol = il.simulate(p, t_end=t_end, t_record=0.0, x0=x0, v0=v0, phase=0.0)
    except ValueError:
        return None
    px, pv = np.asarray(sol.poincare.x), np.asarray(sol.poincare.v)
    scale = max(1.0, abs(x0), abs(v0))
    for n in range(1, min(MAX_PERIOD, px.size - 1) + 1):
        if max(abs(px[n] - x0), abs(pv[n] - v0)) <= RETURN_RTOL * scale:
            break
    else:
        return None
    orb = il.periodic_orbit(p, n, x0=x0, v0=v0, phase=0.0)
    if (not orb.converged or orb.sticks
            or max(abs(orb.x - x0), abs(orb.v - v0)) > START_RTOL * scale):
        return None
    away = np.hypot(px[::n] - orb.x, pv[::n] - orb.v) > LEAVE_RTOL * scale
    periods = px.size - 1
    close = int(np.argmax(away)) * n if away.any() else periods
    return OrbitStart(orb, close, periods)


def describe(start: OrbitStart, names: dict) -> str:
    """The caption of a run that starts on an orbit (Markdown): its stability and type,
    the parameters ``names`` (name -> symbol), its multipliers and how long the run
    stays on it."""
    o = start.orbit
    mus = ", ".join(_complex(complex(m)) for m in o.multipliers)
    at = ", ".join(f"{sym} = {getattr(o.params, name):g}" for name, sym in names.items())
    head = f"**{'Stable' if o.stable else 'Unstable'} {o.label} orbit at {at}**"
    run = "the run starts on it at t = 0, no transient"
    if start.close < start.periods:
        return (f"{head}, left after ≈ {start.close} periods; multipliers {mus} ({run}; "
                f"left: its section state off by > {LEAVE_RTOL:g} · max(1, |x₀|, |v₀|)).")
    return f"{head}, kept for all {start.periods} periods; multipliers {mus} ({run})."


def _complex(z: complex) -> str:
    if abs(z.imag) < 1e-12 * max(1.0, abs(z)):
        text = f"{z.real:.4g}"
    else:
        text = f"{z.real:.4g} {'+' if z.imag >= 0 else '-'} {abs(z.imag):.4g}i"
    return text.replace("-", "−") if math.isfinite(z.real) else text
