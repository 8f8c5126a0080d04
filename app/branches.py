"""Periodic branches over the bifurcation diagram's range, continued from the orbits its
sweep finds (``il.continuation``): what makes a transition seen in the dots a located
event (period doubling, saddle-node, Neimark-Sacker, grazing).

Seeds come from the finished diagram: each run of consecutive swept values with the
same number of distinct impact velocities and a negative largest Lyapunov exponent
(a periodic attractor) gives one seed, its middle value, longest runs first; then the
values the boundary overlay seeds from (``range_seeds``: spread over the parameter's
default range, as the regime map's), so that every orbit whose events the boundary
curves follow at the map's y value is a branch here too and the two views show the
same events; last, where the boundary curves on the regime map (``app.boundaries``, when
its x is the diagram's parameter) cross the line of the current y value, the curve's
orbit there (``curve_seeds``), so that the diagram marks every crossing, a bent curve's
second one and those of curves seeded from the map's regions included. At a value seed
the orbit the motion settles on (``app.stability.settled_orbit``, from the diagram's own
start and window) is continued down to the range's start and up to its end; at each
period doubling the doubled branch is continued too; at a curve's crossing the curve's
orbit is brought to the line from the curve's points either side of it (continued in y)
and continued both ways. A seed whose orbit lies on a branch already found is skipped.

The work is bounded (``MAX_SEEDS`` seeds, ``MAX_POINTS`` points per branch, at most
``WALL_TIME`` seconds), checks between continuations whether it is still wanted, and
complete results are kept for all sessions (LRU by ``Run.diagram_key()`` and the
crossings).
"""
from __future__ import annotations

import logging
import math
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

import impactlib as il

from .settings import SWEEP_RANGES
from .stability import exact_run, settled_orbit
from .state import Run

log = logging.getLogger(__name__)

MAX_SEEDS = 8
#: Seeds spread over a parameter's default range (the regime map's), shared with the
#: boundary overlay (``app.boundaries``).
RANGE_SEEDS = 6
MAX_POINTS = 300
MAX_POINTS_DOUBLED = 150
#: Periods beyond this are not followed (doubled branches of doubled branches...).
MAX_PERIOD = 8
WALL_TIME = 20.0
#: A seed's orbit whose impact velocities are this close (relative) to a branch's is on it.
SAME_ORBIT_RTOL = 1e-3
CACHE_ITEMS = 32
#: Points of the continuation in y from a curve's point to the diagram's line.
CROSSING_POINTS = 60
SHORT = {"period-doubling": "PD", "saddle-node": "SN", "neimark-sacker": "NS",
         "grazing": "graze"}


@dataclass(frozen=True)
class BranchSet:
    """Branches continued over one diagram's range.

    branches : list of il.Branch (swept parameter ``name``).
    complete : every seed was handled (not cut by the time bound or a cancel).
    message : what was done, in words.
    """

    name: str
    branches: tuple
    complete: bool
    message: str

    @property
    def events(self) -> list:
        return [e for b in self.branches for e in b.events]


def seeds(values: np.ndarray, lam: np.ndarray, rows: np.ndarray, drawn_rows: np.ndarray,
          max_seeds: int = MAX_SEEDS) -> list[float]:
    """Seed values from a diagram: ``values`` and ``lam`` per swept value (and chain),
    ``rows`` the value of each recorded impact and ``drawn_rows`` the indices of the
    distinct ones."""
    values, first = np.unique(values, return_index=True)    # one chain of "both"
    lam = lam[first]
    shown = rows[drawn_rows]
    counts = np.array([np.count_nonzero(shown == w) for w in values])
    periodic = np.isfinite(lam) & (lam < 0) & (counts > 0)
    runs, start = [], 0
    for i in range(1, values.size + 1):
        if i == values.size or periodic[i] != periodic[start] or counts[i] != counts[start]:
            if periodic[start]:
                runs.append((i - start, values[(start + i - 1) // 2]))
            start = i
    runs.sort(key=lambda r: -r[0])
    return [float(w) for _, w in runs[:max_seeds]]


def range_seeds(name: str, lo: float = -math.inf, hi: float = math.inf,
                count: int | None = None) -> list[float]:
    """``count`` values (default ``RANGE_SEEDS``) spread over ``name``'s default range
    (its ends left out), those within [lo, hi]."""
    a, b = SWEEP_RANGES[name]
    count = RANGE_SEEDS if count is None else count
    return [float(w) for w in np.linspace(a, b, count + 2)[1:-1] if lo <= w <= hi]


def on_branch(branches, orb, name: str, value: float) -> bool:
    """Whether ``orb`` (found at ``name`` = value) lies on one of ``branches``: the same
    period and the same impact velocities (which do not depend on where in its cycle the
    orbit crosses the section), interpolated along the branch at ``value``."""
    mine = np.sort(orb.impact_velocities)
    scale = max(1.0, float(np.max(np.abs(mine))))
    for b in branches:
        if b.n != orb.n or b.impacts != mine.size or b.param.size < 2:
            continue
        for i in np.flatnonzero((b.param[:-1] - value) * (b.param[1:] - value) <= 0):
            a, c = b.param[i], b.param[i + 1]
            f = 0.0 if c == a else (value - a) / (c - a)
            u = b.impact_velocities[i] + f * (b.impact_velocities[i + 1] - b.impact_velocities[i])
            if np.max(np.abs(np.sort(u) - mine)) < SAME_ORBIT_RTOL * scale:
                return True
    return False


def curve_seeds(curves, name: str, value: float, lo: float, hi: float) -> tuple:
    """Where boundary ``curves`` (il.Boundary in (``name``, y)) cross y = ``value`` within
    [lo, hi] of ``name``: one (x, y name, n, ends) per crossing, ``ends`` the (x, y, x0,
    v0) of the curve's two points either side of the line (orbit states on them)."""
    seeds = []
    for b in curves:
        if b.names[0] != name or len(b.values) < 2:
            continue
        w, y = b.values[:, 0], b.values[:, 1]
        for i in np.flatnonzero((y[:-1] - value) * (y[1:] - value) <= 0):
            f = 0.0 if y[i + 1] == y[i] else (value - y[i]) / (y[i + 1] - y[i])
            x = w[i] + f * (w[i + 1] - w[i])
            if lo <= x <= hi:
                ends = tuple((float(w[j]), float(y[j]), float(b.x[j]), float(b.v[j]))
                             for j in (i, i + 1))
                seeds.append((round(float(x), 10), b.names[1], b.n, ends))
    return tuple(sorted(set(seeds)))


def _follow(p, name, stop, n, x0, v0, max_points):
    """il.continuation, or None where the core refuses the start (e.g. a stop outside
    the parameter's valid range): one branch less, not a failed overlay."""
    try:
        return il.continuation(p, name, stop, n=n, x0=x0, v0=v0, max_points=max_points)
    except ValueError as exc:
        log.info("branch from %s = %g not continued: %s", name, getattr(p, name), exc)
        return None


def _crossing_orbits(run: Run, seed: tuple):
    """(value, orbit) of a curve's crossing ``seed`` (see ``curve_seeds``): the curve's
    orbit at each of the two points beside the line continued in y, at that point's x,
    to the line (the region of an orbit can be narrower than a step of the curve, so a
    start off the curve in x may find another orbit); none where it does not get there
    (beyond a grazing on the way, say)."""
    name = run.bif_param
    _, name_y, n, ends = seed
    value = getattr(run.params, name_y)
    for x, y, x0, v0 in ends:
        if y == value or not run.bif_min <= x <= run.bif_max:
            continue
        p = run.params.replace(**{name: x, name_y: y})
        try:
            br = il.continuation(p, name_y, value, n=n, x0=x0, v0=v0,
                                 max_points=CROSSING_POINTS)
        except ValueError:
            continue
        if br.param.size and abs(br.param[-1] - value) <= 1e-12 * max(1.0, abs(value)):
            orb = il.periodic_orbit(run.params.replace(**{name: x}), n, x0=float(br.x[-1]),
                                    v0=float(br.v[-1]))
            if orb.converged and not orb.sticks:
                yield x, orb


def compute(run: Run, seed_values: list[float], live=lambda: True,
            orbit_seeds: tuple = (), found: tuple = ()) -> BranchSet:
    """Continue the orbits found at ``seed_values`` of the swept parameter
    ``run.bif_param`` over [run.bif_min, run.bif_max], then those at boundary curves'
    crossings ``orbit_seeds`` (``curve_seeds``), besides the branches ``found``."""
    tic = time.perf_counter()
    name = run.bif_param
    lo, hi = run.bif_min, run.bif_max
    found = list(found)
    done = 0
    starts = [(w, None) for w in seed_values] + [(None, s) for s in orbit_seeds]
    for w, crossing in starts:
        if not live() or time.perf_counter() - tic > WALL_TIME:
            break
        done += 1
        if crossing is not None:
            for w, orb in _crossing_orbits(run, crossing):
                if not on_branch(found, orb, name, w):
                    p = run.params.replace(**{name: w})
                    found += [b for b in (_follow(p, name, stop, orb.n, orb.x, orb.v,
                                                  MAX_POINTS) for stop in (lo, hi))
                              if b is not None and b.param.size > 1]
            continue
        p = run.params.replace(**{name: w})
        orb = settled_orbit(exact_run((p, run.x0, run.v0, run.t_end, run.t_record), None))
        if (orb is None or orb.sticks or not 0 < orb.impacts < math.inf
                or on_branch(found, orb, name, w)):
            continue
        new = [_follow(p, name, stop, orb.n, orb.x, orb.v, MAX_POINTS)
               for stop in (lo, hi) if stop != w]
        new = [b for b in new if b is not None and b.param.size > 1]
        found += new
        for b in new:
            for e in b.events:
                if e.kind != "period-doubling" or 2 * b.n > MAX_PERIOD:
                    continue
                if not live() or time.perf_counter() - tic > WALL_TIME:
                    break
                stop = hi if e.value < hi else lo
                d = _follow(e.params, name, stop, 2 * b.n, e.x, e.v, MAX_POINTS_DOUBLED)
                if d is not None and d.param.size > 1:
                    found.append(d)
    complete = done == len(starts) and live()
    events = sum(len(b.events) for b in found)
    cut = "" if complete else " (stopped at the time bound)"
    message = (f"{len(found)} pieces from {done} of {len(starts)} seeds, {events} "
               f"events, {time.perf_counter() - tic:.1f} s{cut}")
    return BranchSet(name, tuple(found), complete, message)


class BranchCache:
    """Complete result sets (branches by diagram key, boundary curves by request key):
    least recently used dropped first; an incomplete set is not kept."""

    def __init__(self, max_items: int = CACHE_ITEMS):
        self.max_items = max_items
        self._items: OrderedDict = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key):
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        return None

    def put(self, key, value) -> None:
        if not value.complete:
            return
        with self._lock:
            self._items[key] = value
            self._items.move_to_end(key)
            while len(self._items) > self.max_items:
                self._items.popitem(last=False)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()


CACHE = BranchCache()


def branches_for(run: Run, diagram: dict, ticket=None, orbit_seeds: tuple = ()) -> BranchSet:
    """The branch set of ``run``'s diagram (``diagram``: the merged chunks, see
    ``app.diagram.merged``), seeded also at boundary curves' crossings ``orbit_seeds``
    (``curve_seeds``), from the cache or computed (the work of a session's branch job; it
    stops early once ``ticket`` is no longer live)."""
    key = (run.diagram_key(), orbit_seeds)
    hit = CACHE.get(key)
    if hit is not None:
        return hit
    live = (lambda: ticket.live) if ticket is not None else (lambda: True)
    own = CACHE.get((run.diagram_key(), ()))
    if own is not None and orbit_seeds:      # the diagram's own branches, and the crossings
        result = compute(run, [], live, orbit_seeds, own.branches)
    else:
        sv = seeds(diagram["values"], diagram["lyapunov"], diagram["omega"], diagram["drawn"])
        sv += [w for w in range_seeds(run.bif_param, run.bif_min, run.bif_max)
               if w not in sv]
        result = compute(run, sv, live, orbit_seeds)
    CACHE.put(key, result)
    return result
