"""Regime maps and basins of attraction for the research views: bounded and streamed.

Both are long computations run by a session's research job (app.explorer, one heavy job
per session, in a thread of ``_POOL`` there, never on the event loop). Each is a
generator of row blocks that the job forwards to its view; stopping the iteration
cancels what has not started. Every request is bounded: cells per side by the settings
(``MAP_N_MAX``, ``BASINS_N_MAX``), wall time by ``MAP_WALL_TIME`` / ``BASINS_WALL_TIME``
(the rows done so far stay, with a message saying so), work per cell by the ceilings
below. Nothing here knows about Panel.
"""
from __future__ import annotations

import dataclasses
import math
import os
import time

import numpy as np

import impactlib as il
from impactlib.analysis.classify import describe
from impactlib.sweeps import distributed as ild

from .settings import SWEEP_RANGES
from .state import Run

#: Wall time of one regime map / basins picture; rows not started by then are left out.
MAP_WALL_TIME = 30.0
BASINS_WALL_TIME = 20.0
#: Work ceilings per cell of the regime map, whatever the window (the paper's window
#: needs <= 11.3k steps and 2.3k impacts): a block of rows cannot be interrupted, so a
#: cell's worst cost (~0.1 s here) bounds how far a block overruns the wall time. Longer
#: windows end cells at a ceiling, counted in the message.
MAP_MAX_STEPS = 50_000
MAP_MAX_IMPACTS = 5_000
#: Rows of the map per block: the first block is small so the first rows show at once;
#: later blocks are sized from the measured rate to take about BLOCK_SECONDS.
FIRST_ROWS = 2
BLOCK_SECONDS = 0.4
MAX_BLOCK_ROWS = 32
#: On a Dask cluster the map goes in blocks of this many rows, all submitted at once:
#: small enough that the first rows show after one block's work, large enough that the
#: scheduler's cost per task (milliseconds) stays small against it.
CLUSTER_ROWS = 4
#: Basins: periods followed per start before it counts as not settled.
BASINS_MAX_PERIODS = 1000

# -- regime map ---------------------------------------------------------------------------

#: Legend classes besides periodic (m, n): one colour each, keyed by classify's kind.
#: "unbounded" and any kind classify does not know yet fall into their own classes.
FIXED_CLASSES = ("complete chattering", "chaotic", "no impact", "not settled",
                 "undetermined", "unbounded", "other periodic", "other")
FIXED_COLOURS = ("#7b3294", "#1b1b1b", "#d9d9d9", "#f4a6b8", "#ffffff", "#b2182b",
                 "#bf9f6a", "#8c8c8c")
#: Periodic (m, n) classes get their own colour, in order of appearance (row by row, cell
#: by cell), up to this cut-off; later ones are "other periodic".
PERIODIC_COLOURS = ("#4e79a7", "#59a14f", "#f28e2b", "#76b7b2", "#edc948", "#e15759",
                    "#b07aa1", "#9c755f", "#17becf", "#a0cbe8", "#8cd17d", "#ffbe7d")
PALETTE = FIXED_COLOURS + PERIODIC_COLOURS


class RegimeClasses:
    """Stable class indices (into ``PALETTE``) for (m, n) codes as rows arrive: an index
    never changes meaning, so rows drawn earlier stay right."""

    def __init__(self):
        self.labels = list(FIXED_CLASSES)
        self._periodic: dict[tuple[int, int], int] = {}
        self.counts = np.zeros(len(PALETTE), dtype=np.int64)

    def index(self, m: int, n: int) -> int:
        motion = describe(m, n)
        if motion.kind != "periodic":
            kind = motion.kind if motion.kind in FIXED_CLASSES else "other"
            return FIXED_CLASSES.index(kind)
        key = (m, n)
        if key not in self._periodic:
            if len(self._periodic) == len(PERIODIC_COLOURS):
                return FIXED_CLASSES.index("other periodic")
            self._periodic[key] = len(self.labels)
            self.labels.append(motion.label)
        return self._periodic[key]

    def classes(self, impacts: np.ndarray, period: np.ndarray) -> np.ndarray:
        """Class index of each cell (same shape as the code arrays); counts updated."""
        pairs, first, inverse = np.unique(np.stack([impacts.ravel(), period.ravel()], axis=1),
                                          axis=0, return_index=True, return_inverse=True)
        idx = np.empty(len(pairs), dtype=np.int64)
        # colours in order of first appearance cell by cell, row by row: the same whatever
        # the blocks the rows came in (their sizes follow the measured rate)
        for j in np.argsort(first, kind="stable"):
            idx[j] = self.index(int(pairs[j, 0]), int(pairs[j, 1]))
        out = idx[inverse.ravel()].reshape(impacts.shape)
        np.add.at(self.counts, out.ravel(), 1)
        return out

    def legend(self) -> list[tuple[str, str, int]]:
        """(colour, label, cells) of every class seen so far, commonest first."""
        seen = [(PALETTE[i], self.labels[i], int(self.counts[i]))
                for i in range(len(self.labels)) if self.counts[i]]
        return sorted(seen, key=lambda item: -item[2])


@dataclasses.dataclass(frozen=True)
class MapRequest:
    """One regime map: ``run``'s parameters with ``name_x`` and ``name_y`` swept over
    their default ranges (``settings.SWEEP_RANGES``) on an n x n grid."""

    run: Run
    name_x: str
    name_y: str
    n: int

    @property
    def values_x(self) -> np.ndarray:
        return np.linspace(*SWEEP_RANGES[self.name_x], self.n)

    @property
    def values_y(self) -> np.ndarray:
        return np.linspace(*SWEEP_RANGES[self.name_y], self.n)

    def key(self) -> tuple:
        """What the map depends on: everything but the two swept parameters' values."""
        p = dataclasses.replace(self.run.params,
                                **{self.name_x: SWEEP_RANGES[self.name_x][0],
                                   self.name_y: SWEEP_RANGES[self.name_y][0]})
        r = self.run
        return (p, self.name_x, self.name_y, self.n, r.t_end, r.t_record, r.x0, r.v0)


def map_request(run: Run) -> MapRequest:
    return MapRequest(run, run.map_x, run.map_y, run.map_n)


@dataclasses.dataclass(frozen=True)
class MapRows:
    """A block of finished rows of a regime map (rows of y, bottom first)."""

    start: int
    classes: np.ndarray          # (rows, n) indices into PALETTE
    impacts: np.ndarray          # (rows, n) m codes of classify
    period: np.ndarray           # (rows, n) n codes
    legend: list                 # RegimeClasses.legend() after this block
    labels: tuple                # label of each class index so far
    rows_done: int
    rows_total: int
    limited: int                 # cells so far stopped at a work ceiling
    elapsed: float
    message: str


def block_rows(done: int, elapsed: float) -> int:
    """Rows of the next block of a map computed here: FIRST_ROWS first, then about
    BLOCK_SECONDS of work at the rate measured so far."""
    if done == 0:
        return FIRST_ROWS
    rate = done / max(elapsed, 1e-6)
    return int(min(max(os.cpu_count() or 1, rate * BLOCK_SECONDS), MAX_BLOCK_ROWS))


def map_rows(req: MapRequest, wall_time: float = MAP_WALL_TIME, client=None):
    """Stream the regime map of ``req`` in blocks of rows (``MapRows``).

    The blocks are the library's stream (``il.iter_regime_map``: cells are independent,
    so the rows of a map are the map of those rows), here in blocks sized by
    ``block_rows``, or with a Dask ``client`` on its cluster in blocks of
    ``CLUSTER_ROWS`` rows (the same cells either way). Stop iterating to cancel. Raises
    ValueError (from the core) for parameters it refuses, before any block.
    """
    run = req.run
    vx, vy = req.values_x, req.values_y
    opts = dict(t_end=run.t_end, t_record=run.t_record, method="exact", x0=run.x0,
                v0=run.v0, max_steps=MAP_MAX_STEPS, max_impacts=MAP_MAX_IMPACTS)
    if client is None:
        parts = il.iter_regime_map(run.params, req.name_x, vx, req.name_y, vy,
                                   rows=block_rows, **opts)
    else:
        parts = ild.iter_regime_map(client, run.params, req.name_x, vx, req.name_y, vy,
                                    rows_per_task=CLUSTER_ROWS,
                                    **opts)
    classes = RegimeClasses()
    tic = time.perf_counter()
    done = limited = 0
    try:
        for rm in parts:
            limited += int(np.count_nonzero((rm.status == il.RunStatus.IMPACT_LIMIT)
                                            | (rm.status == il.RunStatus.STEP_LIMIT)))
            start, done = done, done + rm.values_y.size
            elapsed = time.perf_counter() - tic
            stopped = done < vy.size and elapsed > wall_time
            notes = []
            if stopped:
                notes.append(f"stopped at the time limit ({wall_time:g} s) after {done} of "
                             f"{vy.size} rows")
            if limited:
                notes.append(f"{limited} cells stopped at a work ceiling")
            cells = classes.classes(rm.impacts, rm.period)
            yield MapRows(start, cells, rm.impacts, rm.period,
                          classes.legend(), tuple(classes.labels), done, vy.size, limited,
                          elapsed, "; ".join(notes) or "complete")
            if stopped:
                return
    finally:
        parts.close()


# -- basins ---------------------------------------------------------------------------

#: Colours of the attractors (by index, cycled), and of undecided starts.
BASIN_COLOURS = ("#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#b07aa1", "#76b7b2",
                 "#edc948", "#9c755f", "#17becf", "#bcbd22")
UNDECIDED = "#e8e8e8"
#: Smallest half-width of the window (units of x and v).
MIN_SPAN = 0.2


@dataclasses.dataclass(frozen=True)
class BasinsRequest:
    """Basins of ``run``'s parameters on the section t = 0 (the scene's start time), over
    a window around the scene's motion."""

    run: Run
    x_range: tuple
    v_range: tuple
    n: int

    def key(self) -> tuple:
        """What the picture depends on (not the start (x0, v0) of the scene)."""
        r = self.run
        return (r.params, self.x_range, self.v_range, self.n)


def basins_window(run: Run, trajectory: dict | None) -> tuple[tuple, tuple]:
    """(x_range, v_range): x from the wall g to twice the motion's reach beyond it, v
    over twice its largest speed either way, both taking in the scene's start."""
    g = run.params.g
    x0 = run.x0 if run.x0 is not None else max(0.0, g)
    reach, speed = MIN_SPAN, MIN_SPAN
    if trajectory is not None and len(trajectory["x"]):
        reach = max(reach, 2.0 * float(np.max(np.asarray(trajectory["x"]) - g)))
        speed = max(speed, 2.0 * float(np.max(np.abs(trajectory["v"]))))
    reach = max(reach, 1.1 * (x0 - g))
    speed = max(speed, 1.1 * abs(run.v0))
    return (g, g + _nice(reach)), (-_nice(speed), _nice(speed))


def _nice(x: float) -> float:
    """x rounded up to two significant digits (a window that reads well on the axes)."""
    e = 10.0 ** (math.floor(math.log10(x)) - 1)
    return round(math.ceil(x / e) * e, 12)


def basins_rows(req: BasinsRequest, wall_time: float = BASINS_WALL_TIME, client=None):
    """Stream the basins of ``req`` (``il.BasinRows`` blocks), here or with a Dask
    ``client`` on its cluster (the same blocks). Raises ValueError (the core's message)
    for a window or parameters it refuses."""
    args = (req.run.params, req.x_range, req.v_range)
    opts = dict(n=(req.n, req.n), phase=0.0, max_periods=BASINS_MAX_PERIODS,
                time_limit=wall_time)
    if client is None:
        return il.iter_basins(*args, **opts)
    return ild.iter_basins(client, *args, **opts)


def attractor_text(att) -> str:
    """'3-impact period-3 at (0.123, -0.456)' (two attractors can share a label)."""
    x, v = att.points[0]
    return f"{att.label} through ({x:.3g}, {v:.3g})"
