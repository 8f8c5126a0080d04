"""The live bifurcation diagram: computed off the event loop, streamed, cancellable.

One worker thread per server process runs diagram chunks for every session in FIFO
order (each chunk uses all cores through the core's parallel sweep). A session's
diagram is split into chunks of interleaved omega values, so the whole range fills in
coarse-to-fine and the first points appear at once; chunk sizes adapt to the measured
cost so that slow parameter sets still stream and cancel within a fraction of a second.
Each chunk is a separate job, so sessions take turns and nobody waits for a whole
diagram of someone else. Restarting bumps a generation number: queued chunks of the
old generation are dropped before they run, and results that arrive late are ignored.
The core's kernels release the GIL, so the server's event loop keeps serving.
"""
from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import impactlib as il

from .state import Run

log = logging.getLogger(__name__)

#: Adaptive chunks: the first holds FIRST_CHUNK values (spread over the whole range);
#: later ones are sized from the measured rate to take about CHUNK_SECONDS, and hold at
#: most a quarter of the values (each chunk makes the browser redraw the diagram).
FIRST_CHUNK = 4
CHUNK_SECONDS = 0.25
#: Ceilings: wall time of one diagram; steps and impacts simulated per omega value for
#: each 500 s of simulated time (the paper's diagrams need <= 11.3k steps and 2.3k
#: impacts per value), so a costly value stops early, flagged, instead of running on.
DIAGRAM_WALL_TIME = 20.0
DIAGRAM_MAX_STEPS_PER_500S = 50_000
DIAGRAM_MAX_IMPACTS_PER_500S = 5_000
MAX_CHUNK = 64
#: Points of one omega value closer than this fraction of the largest |v| are drawn once
#: (a period-1 orbit is one dot, not a hundred dots on top of each other).
DRAW_RESOLUTION = 1e-3
#: At most this many impacts per omega value are kept (the first ones of the window).
MAX_IMPACTS_PER_VALUE = 100

_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-diagram")


def omega_values(run: Run) -> np.ndarray:
    return np.linspace(run.bif_min, run.bif_max, run.bif_n)


def chunk_values(values: np.ndarray, n_chunks: int = 4) -> list[np.ndarray]:
    """Interleaved chunks: chunk j holds values[j::n] (each spans the whole range)."""
    n = max(1, min(n_chunks, values.size))
    return [np.ascontiguousarray(values[j::n]) for j in range(n)]


def interleaved(values: np.ndarray, stride: int = 16) -> np.ndarray:
    """values[0::s], values[1::s], ...: every prefix spreads over the whole range, so
    the diagram fills in coarse to fine."""
    return np.concatenate([values[j::stride] for j in range(min(stride, values.size))])


def drawn(omega: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Indices of the rows worth drawing: one per (omega, v quantised to the screen)."""
    if omega.size == 0:
        return np.zeros(0, dtype=np.int64)
    q = DRAW_RESOLUTION * max(1.0, float(np.max(np.abs(v))))
    keys = np.column_stack((omega, np.round(v / q)))
    _, first = np.unique(keys, axis=0, return_index=True)
    return np.sort(first)


def compute_chunk(run: Run, values: np.ndarray) -> dict:
    """Impacts only (no dense output), exact method, independent starts, the core's
    parallel sweep; at most MAX_IMPACTS_PER_VALUE impacts kept per value."""
    scale = max(1.0, run.t_end / 500.0)
    bif = il.bifurcation(run.params, "omega", values, t_end=run.t_end,
                         t_record=run.t_record, method="exact", x0=run.x0, v0=run.v0,
                         warm_start=False, cap_per_value=MAX_IMPACTS_PER_VALUE,
                         max_impacts=int(DIAGRAM_MAX_IMPACTS_PER_500S * scale),
                         max_steps=int(DIAGRAM_MAX_STEPS_PER_500S * scale))
    status = np.asarray(bif.status)
    omega, v = np.asarray(bif.param, dtype=float), np.asarray(bif.v, dtype=float)
    return {"omega": omega, "v": v,
            "t": np.asarray(bif.t, dtype=float), "phase": np.asarray(bif.phase, dtype=float),
            "drawn": drawn(omega, v),
            # 1, 2: a work limit stopped the run; 3 only means more impacts than kept
            "partial": int(np.count_nonzero((status != 0) & (status != 3)))}


class DiagramRunner:
    """Runs one session's diagram. ``dispatch(fn)`` must run ``fn`` on the session's
    event loop (``doc.add_next_tick_callback``); callbacks get the generation number so
    the view can ignore stale results."""

    def __init__(self, dispatch: Callable[[Callable[[], None]], None],
                 on_chunk: Callable[[int, dict, int, int], None],
                 on_done: Callable[[int, dict], None],
                 on_error: Callable[[int, str], None]):
        self._dispatch = dispatch
        self._on_chunk = on_chunk
        self._on_done = on_done
        self._on_error = on_error
        self._lock = threading.Lock()
        self._gen = 0
        self.done = threading.Event()
        self.done.set()

    @property
    def generation(self) -> int:
        return self._gen

    def cancel(self) -> None:
        with self._lock:
            self._gen += 1
        self.done.set()

    def start(self, run: Run) -> int:
        """Cancel any running diagram and start one for ``run``; returns its generation."""
        with self._lock:
            self._gen += 1
            gen = self._gen
        self.done.clear()
        job = _Job(gen, run, interleaved(omega_values(run)), time.perf_counter())
        self._submit(job)
        return gen

    def _current(self, gen: int) -> bool:
        return gen == self._gen

    def _submit(self, job: "_Job") -> None:
        try:
            _POOL.submit(self._work, job)
        except RuntimeError:      # interpreter shutting down
            pass

    def _work(self, job: "_Job") -> None:
        if not self._current(job.gen):
            return
        n = job.order.size
        if job.done == 0:
            size = min(FIRST_CHUNK, n)
        else:
            rate = job.done / max(time.perf_counter() - job.t0, 1e-6)
            size = int(min(max(1, rate * CHUNK_SECONDS), max(1, n // 4), MAX_CHUNK))
        values = job.order[job.done: job.done + size]
        try:
            part = compute_chunk(job.run, np.sort(values))
        except Exception as exc:   # report, never kill the worker, no traceback in the log
            log.warning("bifurcation diagram failed: %s: %s", type(exc).__name__, exc)
            self._send(job.gen, lambda: self._on_error(job.gen, f"{type(exc).__name__}: {exc}"))
            self.done.set()
            return
        if not self._current(job.gen):
            return
        job.partial += part.pop("partial")
        job.done += values.size
        done, elapsed = job.done, time.perf_counter() - job.t0
        self._send(job.gen, lambda: self._on_chunk(job.gen, part, done, n))
        if done >= n or elapsed > DIAGRAM_WALL_TIME:
            info = {"elapsed": elapsed, "partial": job.partial, "done": done, "total": n}
            self._send(job.gen, lambda: self._on_done(job.gen, info))
            self.done.set()
        else:
            self._submit(job)

    def _send(self, gen: int, fn: Callable[[], None]) -> None:
        def guarded():
            if self._current(gen):
                fn()
        try:
            self._dispatch(guarded)
        except Exception as exc:   # the session went away
            log.info("diagram result dropped: %s", exc)
            self.cancel()


class _Job:
    """One diagram in progress (touched by one worker at a time)."""

    def __init__(self, gen: int, run: Run, order: np.ndarray, t0: float):
        self.gen, self.run, self.order, self.t0 = gen, run, order, t0
        self.done = 0
        self.partial = 0
