"""Seeds of the boundary overlay from the regime map's periodic cells: where an orbit's
region lies off the line of the current y value, its boundary curves have no event on
that line to start from, so the overlay starts them from the region itself.

A finished map's cells classified periodic (m impacts in n periods) are cut into
connected regions per class (largest first, at least ``MIN_CELLS`` cells, periods up to
``MAX_PERIOD``). A region counts as explained when a drawn curve of the same orbit type
passes within a cell of its bounding box. Otherwise the orbit is found at the region's
innermost cell (a run from the map's own start, ``app.stability.settled_orbit``; a cell
whose run settles on another orbit type is not used, and the next innermost is tried),
continued in x over the whole range at that cell's y, and its period-doubling,
saddle-node and grazing events are the seeds, those on a curve already drawn (same kind,
within ``SAME_POINT`` of the box) left out. Nothing here knows about Panel.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import ndimage

from .branches import _follow
from .settings import SWEEP_RANGES
from .stability import exact_run, settled_orbit

#: Regions smaller than this many cells are left out (single noisy cells).
MIN_CELLS = 4
#: Regions tried per overlay (largest first), and cells tried per region.
MAX_REGIONS = 8
CELLS_PER_REGION = 2
#: Orbits of longer periods are not followed from cells.
MAX_PERIOD = 8
BRANCH_POINTS = 300
#: An event this close to a drawn curve of its kind (a share of the box's sides) is on it.
SAME_POINT = 2e-3


class MapCells:
    """The classified cells of one regime map (``key``: its request's key), handed from the
    session that computes the map to the overlay: filled once the map is done (on the
    session's event loop), or given up when it is cancelled or fails. The overlay never
    waits for them (a thread of the shared research pool must not wait for a map that may
    need it): it uses them when they are there, and the session asks again once they are."""

    def __init__(self, key):
        self.key = key
        self.values_x = self.values_y = self.impacts = self.period = None
        self.complete = False
        self.filled = False
        self.given_up = False

    @classmethod
    def of(cls, key, values_x, values_y, impacts, period, complete=True) -> "MapCells":
        cells = cls(key)
        cells.fill(values_x, values_y, impacts, period, complete)
        return cells

    def fill(self, values_x, values_y, impacts, period, complete: bool = True) -> None:
        """The map's grid and codes (rows of y, bottom first); ``complete`` False for a map
        cut short (its rows not computed hold no periodic cell)."""
        self.values_x, self.values_y = np.asarray(values_x), np.asarray(values_y)
        self.impacts, self.period = np.array(impacts), np.array(period)
        self.complete = complete
        self.filled = True          # last: a reader sees the arrays once this is set

    def give_up(self) -> None:
        """The map will not finish (cancelled, failed)."""
        self.given_up = not self.filled


@dataclasses.dataclass(frozen=True)
class Region:
    """A connected region of one periodic class: ``m`` impacts in ``n`` periods,
    ``cells`` its size, ``box`` (x0, x1, y0, y1) its cells' extent, ``inner`` (x, y) of
    its cells innermost first."""

    m: int
    n: int
    cells: int
    box: tuple
    inner: tuple


def regions(cells: MapCells, min_cells: int = MIN_CELLS) -> list[Region]:
    """The periodic regions of the map, largest first."""
    vx, vy, imp, per = cells.values_x, cells.values_y, cells.impacts, cells.period
    periodic = (imp > 0) & (per > 0) & (per <= MAX_PERIOD)
    found = []
    for m, n in sorted(set(zip(imp[periodic].tolist(), per[periodic].tolist()))):
        labels, count = ndimage.label((imp == m) & (per == n))
        for k in range(1, count + 1):
            mask = labels == k
            size = int(np.count_nonzero(mask))
            if size < min_cells:
                continue
            # deepest first (distance to the nearest cell outside the region, the map's
            # edges included), of equal depth the nearest to the region's centre
            depth = ndimage.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
            rows, cols = np.nonzero(mask)
            off = np.hypot(rows - rows.mean(), cols - cols.mean())
            order = np.lexsort((off, -depth[rows, cols]))[:CELLS_PER_REGION]
            inner = tuple((float(vx[cols[i]]), float(vy[rows[i]])) for i in order)
            found.append(Region(m, n, size, (float(vx[cols.min()]), float(vx[cols.max()]),
                                             float(vy[rows.min()]), float(vy[rows.max()])),
                                inner))
    return sorted(found, key=lambda r: -r.cells)


def explained(region: Region, curves, cells: MapCells) -> bool:
    """Whether a curve of the region's orbit type passes within a cell of its box."""
    vx, vy = cells.values_x, cells.values_y
    dx = (vx[-1] - vx[0]) / max(vx.size - 1, 1)
    dy = (vy[-1] - vy[0]) / max(vy.size - 1, 1)
    x0, x1, y0, y1 = region.box
    for b in curves:
        if b.impacts != region.m or b.n != region.n or len(b.values) == 0:
            continue
        w, r = b.values[:, 0], b.values[:, 1]
        if np.any((w >= x0 - dx) & (w <= x1 + dx) & (r >= y0 - dy) & (r <= y1 + dy)):
            return True
    return False


def near_curve(curves, kind: str, point, scale) -> bool:
    """Whether a curve of ``kind`` passes within ``SAME_POINT`` of ``point`` (x, y), in
    units of the box's sides ``scale`` (wx, wy)."""
    s = np.asarray(scale, dtype=float)
    p = np.asarray(point, dtype=float) / s
    for b in curves:
        if b.kind != kind or len(b.values) == 0:
            continue
        q = b.values / s
        if len(q) == 1:
            d = np.hypot(*(q[0] - p))
        else:
            a, seg = q[:-1], np.diff(q, axis=0)
            t = np.clip(np.einsum("ij,ij->i", p - a, seg)
                        / np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300), 0.0, 1.0)
            d = np.min(np.hypot(*(a + t[:, None] * seg - p).T))
        if d < SAME_POINT:
            return True
    return False


def region_events(req, region: Region, curves, kinds) -> list:
    """The events of ``kinds`` of the region's orbit, continued in x at the y of its
    innermost cell where a run settles on that orbit type, not on a drawn curve; [] when
    no cell gives the orbit."""
    run, name_x, name_y = req.run, req.name_x, req.name_y
    lo, hi = SWEEP_RANGES[name_x]
    scale = (hi - lo, SWEEP_RANGES[name_y][1] - SWEEP_RANGES[name_y][0])
    for x, y in region.inner:
        p = run.params.replace(**{name_x: x, name_y: y})
        orb = settled_orbit(exact_run((p, run.x0, run.v0, run.t_end, run.t_record), None))
        if (orb is None or orb.sticks or orb.n != region.n or orb.impacts != region.m
                or not math.isfinite(orb.x)):
            continue
        found, seen = [], set()
        for stop in (lo, hi):
            b = _follow(p, name_x, stop, orb.n, orb.x, orb.v, BRANCH_POINTS)
            for e in () if b is None else b.events:
                key = (e.kind, round(e.value, 6))
                if (e.kind in kinds and key not in seen
                        and not near_curve(curves, e.kind, (e.value, y), scale)):
                    seen.add(key)
                    found.append(e)
        return found
    return []
