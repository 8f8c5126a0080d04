"""Boundary curves over the regime map's box: where period-doubling, saddle-node and
grazing events of the periodic orbits lie in the map's two parameters (``il.boundary``).

Seeds: first the one-parameter branches in the map's x parameter at the current value of
its y parameter, found as ``app.branches`` finds the diagram's (the orbit a run from the
session's start settles on, at ``SEEDS`` values spread over the x range, continued over
the whole range; a seed on a branch already found is skipped).  Each of their
period-doubling, saddle-node and grazing events is followed in y to both ends of the y
range: the first of each kind, then those next to a stable stretch of their branch
(edges the map shows) before the others, short orbits before long ones.  Then, once the
map is done, its periodic regions that no drawn curve explains (``app.map_seeds``): a
region off the current y line has no event on it.  An event on a curve already drawn is
not followed again.  The work is bounded (``WALL_TIME``, ``MAX_POINTS`` per curve),
streamed curve by curve, stopped between curves once no longer wanted, and complete
sets are kept for all sessions (LRU by the request's key).  Nothing here knows about
Panel.
"""
from __future__ import annotations

import collections
import dataclasses
import logging
import math
import time

import numpy as np

import impactlib as il

from . import map_seeds
from .branches import RANGE_SEEDS, BranchCache, _follow, on_branch, range_seeds
from .settings import SWEEP_RANGES
from .stability import exact_run, settled_orbit
from .state import Run

log = logging.getLogger(__name__)

KINDS = ("period-doubling", "saddle-node", "grazing")
SEEDS = RANGE_SEEDS
BRANCH_POINTS = 300
MAX_POINTS = 800
#: Largest move along a curve per step, as a share of the y range (a line on the map).
STEP = 0.01
WALL_TIME = 30.0
CACHE_ITEMS = 16


@dataclasses.dataclass(frozen=True)
class BoundaryRequest:
    """The curves of ``run``'s periodic orbits in the box of ``name_x`` x ``name_y`` (their
    default ranges, as the regime map's)."""

    run: Run
    name_x: str
    name_y: str
    #: The map's cells (``map_seeds.MapCells``), also seeds once the map is done; None:
    #: the branches' events only.
    cells: map_seeds.MapCells | None = dataclasses.field(default=None, compare=False)

    def key(self) -> tuple:
        """What the curves depend on: all but the x value (seeds span the x range), and
        the map whose cells seed them."""
        r = self.run
        p = dataclasses.replace(r.params, **{self.name_x: SWEEP_RANGES[self.name_x][0]})
        cells = None if self.cells is None else self.cells.key
        return (p, self.name_x, self.name_y, r.x0, r.v0, r.t_end, r.t_record, cells)


@dataclasses.dataclass(frozen=True)
class BoundarySet:
    """Curves so far: ``curves`` a tuple of il.Boundary; ``done`` curves followed of
    ``total`` asked for, from ``events`` events; ``complete`` nothing was cut;
    ``message`` in words."""

    curves: tuple
    done: int
    total: int
    complete: bool
    message: str
    events: int = 0
    #: The last set of a request whose map was not done yet: ask again once it is.
    waiting: bool = False

    def lines(self, kind: str) -> tuple[list, list]:
        """(xs, ys): one array pair per curve of ``kind``, for a multi-line renderer."""
        picked = [b for b in self.curves if b.kind == kind and len(b.values) > 1]
        return [b.values[:, 0] for b in picked], [b.values[:, 1] for b in picked]


def branch_events(req: BoundaryRequest, live, deadline) -> list:
    """The events of the branches in x at the current y, each kind/orbit/value once."""
    run, name = req.run, req.name_x
    lo, hi = SWEEP_RANGES[name]
    found, events, seen = [], [], set()
    for w in range_seeds(name, count=SEEDS):
        if not live() or time.perf_counter() > deadline:
            break
        p = run.params.replace(**{name: w})
        orb = settled_orbit(exact_run((p, run.x0, run.v0, run.t_end, run.t_record), None))
        if (orb is None or orb.sticks or not 0 < orb.impacts < math.inf
                or on_branch(found, orb, name, w)):
            continue
        new = [_follow(p, name, stop, orb.n, orb.x, orb.v, BRANCH_POINTS) for stop in (lo, hi)]
        new = [b for b in new if b is not None and b.param.size > 1]
        found += new
        for b in new:
            for e in b.events:
                key = (e.kind, b.n, b.impacts, round(e.value, 6))
                if e.kind in KINDS and key not in seen:
                    seen.add(key)
                    # an event next to a stable stretch bounds a region the map shows;
                    # short orbits are cheap and the map's broad regions
                    near = b.stable[max(e.index - 1, 0):e.index + 2]
                    events.append((not bool(np.any(near)), b.n * b.impacts, len(events), e))
    return [item[-1] for item in sorted(events, key=lambda item: item[:3])]


def _followed(jobs, name: str, ds: float, client, wanted=lambda e: True):
    """``il.boundary`` of each (event, stop) in order: one after the other as asked for,
    or with a Dask ``client`` all at once on its cluster (closing cancels the rest). A
    curve the core refuses comes as its ValueError, in its turn; one whose event is no
    longer ``wanted`` (asked in its turn: on a curve drawn since) as None, and is not
    followed here."""
    if client is None:
        for e, stop in jobs:
            if not wanted(e):
                yield None
                continue
            try:
                yield il.boundary(e, name, stop, ds=ds, max_points=MAX_POINTS)
            except ValueError as exc:
                yield exc
        return
    futures = collections.deque(client.map(il.boundary, [e for e, _ in jobs],
                                           [name] * len(jobs), [s for _, s in jobs],
                                           ds=ds, max_points=MAX_POINTS, pure=False))
    try:
        for e, _ in jobs:
            future = futures.popleft()
            if not wanted(e):
                future.cancel()
                yield None
                continue
            try:
                yield future.result()
            except ValueError as exc:
                yield exc
    finally:
        if futures:
            client.cancel(list(futures))


def _jobs(events, name: str) -> list:
    """(event, stop) of each event to both ends of ``name``'s range."""
    lo, hi = SWEEP_RANGES[name]
    return [(e, stop) for e in events for stop in (lo, hi) if stop != getattr(e.params, name)]


def compute(req: BoundaryRequest, live=lambda: True, client=None):
    """Generator of ``BoundarySet`` (all curves so far), one after each curve; with a Dask
    ``client`` the curves are followed on its cluster (the same curves).

    First the events of the branches at the current y (kept for all sessions once
    complete), then, when the map's cells are there (``req.cells`` filled), those of its
    periodic regions no drawn curve explains (``app.map_seeds``); a last set marked
    ``waiting`` when they are not there yet. An event on a curve already drawn (same
    kind, ``map_seeds.SAME_POINT``) is not followed again."""
    tic = time.perf_counter()
    deadline = tic + WALL_TIME
    box = tuple(SWEEP_RANGES[n][1] - SWEEP_RANGES[n][0] for n in (req.name_x, req.name_y))
    curves: list = []
    count = {"done": 0, "total": 0, "events": 0, "cells": 0, "regions": 0}

    def follow(events, note=""):
        """Follow ``events`` to both ends of y; yields a BoundarySet after each curve.
        False (as the generator's value) when cut by the time bound or a cancel."""
        jobs = _jobs(events, req.name_y)
        count["total"] += len(jobs)
        count["events"] += len(events)
        lo, hi = SWEEP_RANGES[req.name_y]
        drawn_from = set()      # events whose curves are followed (not on a drawn one)

        def wanted(e):
            if id(e) in drawn_from:
                return True
            if map_seeds.near_curve(curves, e.kind, (e.value, getattr(e.params, req.name_y)),
                                    box):
                return False
            drawn_from.add(id(e))
            return True

        followed = _followed(jobs, req.name_y, STEP * (hi - lo), client, wanted)
        try:
            for e, stop in jobs:
                if not live() or time.perf_counter() > deadline:
                    return False
                count["done"] += 1
                b = next(followed)
                if b is None:               # on a curve already drawn
                    continue
                if isinstance(b, ValueError):   # e.g. a second parameter it cannot take
                    log.info("boundary from %s not followed: %s", tuple(e), b)
                    continue
                curves.append(b)
                yield BoundarySet(tuple(curves), count["done"], count["total"], False,
                                  f"{count['done']} of {count['total']} curves{note}")
        finally:
            followed.close()
        return True

    cells = req.cells
    first = None if cells is None else CACHE.get(dataclasses.replace(req, cells=None).key())
    if first is not None:           # the branches' curves, kept from an earlier request
        curves += first.curves
        count.update(done=first.done, total=first.total, events=first.events)
        complete = True
        yield dataclasses.replace(first, complete=False,
                                  message=f"{len(curves)} curves; the map's regions next")
    else:
        events = branch_events(req, live, deadline)
        # the first event of each kind, then the rest in order: every kind shows early,
        # and a cut by the time bound leaves the map's main edges drawn
        firsts = [next(e for e in events if e.kind == kind) for kind in KINDS
                  if any(e.kind == kind for e in events)]
        ordered = firsts + [e for e in events if not any(e is f for f in firsts)]
        yield BoundarySet((), 0, 2 * len(ordered), False, f"{len(events)} events to follow")
        complete = yield from follow(ordered)
        complete = complete and live()
        if cells is not None:       # kept as a request without cells would keep them
            CACHE.put(dataclasses.replace(req, cells=None).key(),
                      BoundarySet(tuple(curves), count["done"], count["total"], complete,
                                  f"{len(curves)} curves from {count['events']} events, "
                                  f"{time.perf_counter() - tic:.1f} s", count["events"]))
    waiting = complete and cells is not None and not cells.filled and not cells.given_up
    if complete and cells is not None and cells.filled:
        complete = cells.complete
        for region in map_seeds.regions(cells):
            if not live() or time.perf_counter() > deadline:
                complete = False
                break
            if count["regions"] == map_seeds.MAX_REGIONS:
                break
            if map_seeds.explained(region, curves, cells):
                continue
            count["regions"] += 1
            found = map_seeds.region_events(req, region, curves, KINDS)
            count["cells"] += len(found)
            if not (yield from follow(found, " (from the map's cells)")):
                complete = False
                break
    complete = complete and live() and not waiting and not (cells is not None
                                                            and cells.given_up)
    cut = ("" if complete else " (cancelled)" if not live()
           else "; the map's regions once it is done" if waiting
           else " (without the map's regions: the map did not finish)"
           if cells is not None and cells.given_up and count["done"] == count["total"]
           else " (stopped at the time bound)")
    from_cells = (f", {count['cells']} of them from {count['regions']} regions of the map"
                  if cells is not None and cells.filled else "")
    yield BoundarySet(tuple(curves), count["done"], count["total"], complete,
                      f"{len(curves)} curves from {count['events']} events{from_cells}, "
                      f"{time.perf_counter() - tic:.1f} s{cut}", count["events"], waiting)


CACHE = BranchCache(CACHE_ITEMS)      # complete boundary sets by request key


def boundary_sets(req: BoundaryRequest, live=lambda: True, client=None):
    """The curves of ``req`` as a stream of ``BoundarySet``: from the cache at once, or
    computed (here, or on the cluster of a Dask ``client``) and kept once complete."""
    hit = CACHE.get(req.key())
    if hit is not None:
        yield hit
        return
    last = None
    for last in compute(req, live, client):
        yield last
    if last is not None:
        CACHE.put(req.key(), last)
