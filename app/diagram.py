"""The live bifurcation diagram: computed off the event loop, streamed, cancellable.

One worker thread per server process runs diagram chunks for every session in FIFO
order. A session's diagram is split into interleaved chunks (every n-th omega value),
so the whole omega range fills in coarse-to-fine and the first points appear at once.
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

#: Chunks per diagram (values are interleaved across chunks). Every chunk makes the
#: browser redraw the diagram, so a few are better than many.
N_CHUNKS = 4
#: Points of one omega value closer than this fraction of the largest |v| are drawn once
#: (a period-1 orbit is one dot, not a hundred dots on top of each other).
DRAW_RESOLUTION = 1e-3
#: At most this many impacts per omega value are kept (the first ones of the window).
MAX_IMPACTS_PER_VALUE = 100

_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-diagram")


def omega_values(run: Run) -> np.ndarray:
    return np.linspace(run.bif_min, run.bif_max, run.bif_n)


def chunk_values(values: np.ndarray, n_chunks: int = N_CHUNKS) -> list[np.ndarray]:
    """Interleaved chunks: chunk j holds values[j::n] (the first chunk spans the range)."""
    n = max(1, min(n_chunks, values.size))
    return [np.ascontiguousarray(values[j::n]) for j in range(n)]


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
    bif = il.bifurcation(run.params, "omega", values, t_end=run.t_end,
                         t_record=run.t_record, method="exact", x0=run.x0, v0=run.v0,
                         warm_start=False, cap_per_value=MAX_IMPACTS_PER_VALUE)
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
                 on_done: Callable[[int, float, int], None],
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
        chunks = chunk_values(omega_values(run))
        self._submit(gen, run, chunks, 0, time.perf_counter(), 0)
        return gen

    def _current(self, gen: int) -> bool:
        return gen == self._gen

    def _submit(self, gen, run, chunks, i, t0, partial) -> None:
        try:
            _POOL.submit(self._work, gen, run, chunks, i, t0, partial)
        except RuntimeError:      # interpreter shutting down
            pass

    def _work(self, gen, run, chunks, i, t0, partial) -> None:
        if not self._current(gen):
            return
        try:
            part = compute_chunk(run, chunks[i])
        except Exception as exc:   # report, never kill the worker, no traceback in the log
            log.warning("bifurcation diagram failed: %s: %s", type(exc).__name__, exc)
            self._send(gen, lambda: self._on_error(gen, f"{type(exc).__name__}: {exc}"))
            self.done.set()
            return
        if not self._current(gen):
            return
        partial += part.pop("partial")
        n = len(chunks)
        last_chunk = i + 1 == n
        self._send(gen, lambda: self._on_chunk(gen, part, i + 1, n))
        if last_chunk:
            elapsed = time.perf_counter() - t0
            self._send(gen, lambda: self._on_done(gen, elapsed, partial))
            self.done.set()
        else:
            self._submit(gen, run, chunks, i + 1, t0, partial)

    def _send(self, gen: int, fn: Callable[[], None]) -> None:
        def guarded():
            if self._current(gen):
                fn()
        try:
            self._dispatch(guarded)
        except Exception as exc:   # the session went away
            log.info("diagram result dropped: %s", exc)
            self.cancel()
