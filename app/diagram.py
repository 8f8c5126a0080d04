"""The live bifurcation diagram: computed once per set of inputs, shared, streamed.

The diagram sweeps ``Run.bif_param`` (any of omega, r, c, g, m, k) over
``linspace(bif_min, bif_max, bif_n)`` in the sweep mode ``Run.bif_sweep``:
``independent`` (every value from (x0, v0), streamed coarse-to-fine) or ``up``, ``down``,
``both`` (continuation: each value starts where its neighbour ended). A continuation is
one sequential chain per direction, so each direction arrives as one chunk; its work per
value is scaled down so that a whole chain stays within WARM_MAX_STEPS and
WARM_MAX_IMPACTS (values that hit the ceiling are counted and reported).

A diagram depends only on ``Run.diagram_key()``. ``CACHE`` holds one ``SharedDiagram``
per key, in flight or finished: a session that asks for a diagram someone else is
computing follows that computation (the chunks so far arrive at once, the rest as they
come); one that asks for a finished diagram gets it at once. The computation stops
when the last session following it leaves. Finished diagrams are kept up to a memory
bound (least recently used dropped first); one cut short by the time limit is not kept.

One worker thread per server process runs the chunks of every computation in FIFO
order (each chunk uses all cores through the core's parallel sweep). A diagram is split
into chunks of interleaved omega values, so the whole range fills in coarse-to-fine and
the first points appear at once; chunk sizes adapt to the measured cost so that slow
parameter sets still stream and stop within a fraction of a second. Each chunk is a
separate task, so computations take turns. The core's kernels release the GIL, so the
server's event loop keeps serving meanwhile.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import impactlib as il

from .settings import SYMBOLS
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
#: Work ceilings of one continuation chain (all its values together): about 12 s of
#: the costliest stepping and 9 s of impacts on this machine at worst; the paper's
#: diagram at 400 values needs a tenth of that.
WARM_MAX_STEPS = 8_000_000
WARM_MAX_IMPACTS = 1_000_000
#: Points of one omega value closer than this fraction of the largest |v| are drawn once
#: (a period-1 orbit is one dot, not a hundred dots on top of each other).
DRAW_RESOLUTION = 1e-3
#: At most this many impacts per omega value are kept (the first ones of the window).
MAX_IMPACTS_PER_VALUE = 100
#: Finished diagrams kept for later sessions: at most this many bytes of chunk arrays
#: (the default diagram holds ~0.5 MB) and this many diagrams.
CACHE_BYTES = 64 * 2**20
CACHE_ITEMS = 128

_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-diagram")


COLUMNS = ("omega", "v", "t", "phase", "direction")
#: Columns with one entry per swept value (not per impact): the value, its largest
#: Lyapunov exponent and the chain that ran it (0 independent, +1 up, -1 down).
PER_VALUE = ("values", "lyapunov", "sweep")


def sweep_values(run: Run) -> np.ndarray:
    """The values of the swept parameter ``run.bif_param``."""
    return np.linspace(run.bif_min, run.bif_max, run.bif_n)


def directions(run: Run) -> tuple[int, ...]:
    """Chains of the sweep mode: (0,) independent, (1,) up, (-1,) down, (1, -1) both."""
    return {"independent": (0,), "up": (1,), "down": (-1,), "both": (1, -1)}[run.bif_sweep]


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


def compute_chunk(run: Run, values: np.ndarray, direction: int = 0) -> dict:
    """Impacts only (no dense output), exact method, at most MAX_IMPACTS_PER_VALUE kept
    per value. ``direction`` 0: independent starts (the core's parallel sweep); +1 / -1:
    one continuation chain over ``values`` upwards / downwards.

    The column ``omega`` holds the swept parameter's value whatever it is (the name
    the diagram's data has always had; ``run.bif_param`` says which parameter it is).
    The same runs carry the tangent dynamics: ``lyapunov`` is the largest Lyapunov
    exponent of each of ``values`` (-inf where the motion sticks, NaN where undefined).
    """
    scale = max(1.0, run.t_end / 500.0)
    max_impacts = int(DIAGRAM_MAX_IMPACTS_PER_500S * scale)
    max_steps = int(DIAGRAM_MAX_STEPS_PER_500S * scale)
    if direction:
        max_impacts = max(100, min(max_impacts, WARM_MAX_IMPACTS // values.size))
        max_steps = max(1000, min(max_steps, WARM_MAX_STEPS // values.size))
    bif = il.bifurcation(run.params, run.bif_param, values, t_end=run.t_end,
                         t_record=run.t_record, method="exact", x0=run.x0, v0=run.v0,
                         warm_start={0: False, 1: "up", -1: "down"}[direction],
                         cap_per_value=MAX_IMPACTS_PER_VALUE, max_impacts=max_impacts,
                         max_steps=max_steps, lyapunov=True)
    status = np.asarray(bif.status)
    omega, v = np.asarray(bif.param, dtype=float), np.asarray(bif.v, dtype=float)
    return {"omega": omega, "v": v,
            "t": np.asarray(bif.t, dtype=float), "phase": np.asarray(bif.phase, dtype=float),
            "direction": np.full(omega.size, direction, dtype=np.int8),
            "drawn": drawn(omega, v),
            # per swept value: the largest Lyapunov exponent over the same window
            "values": np.asarray(bif.values, dtype=float), "lyapunov": bif.lyapunov,
            "sweep": np.full(values.size, direction, dtype=np.int8),
            # 1, 2: a work limit stopped the run; 3 only means more impacts than kept
            "partial": int(np.count_nonzero((status != il.RunStatus.OK)
                                            & (status != il.RunStatus.OUTPUT_FULL)))}


def merged(parts: list[dict]) -> dict:
    """Several chunks as one (``drawn`` indices shifted to the joined arrays)."""
    out = {c: np.concatenate([p[c] for p in parts]) for c in (*COLUMNS, *PER_VALUE)}
    offsets = np.cumsum([0] + [p["omega"].size for p in parts[:-1]])
    out["drawn"] = np.concatenate([p["drawn"] + o for p, o in zip(parts, offsets)])
    return out


def what(run: Run) -> str:
    """'400 ω values' (and the sweep mode unless independent)."""
    mode = {"independent": "", "up": ", swept up", "down": ", swept down",
            "both": ", swept up and down"}[run.bif_sweep]
    return f"{run.bif_n} {SYMBOLS[run.bif_param]} values{mode}"


def status_text(run: Run, info: dict, recorded: int, drawn: int) -> tuple[str, str]:
    """(status line, figure title end) of a finished diagram of ``run``."""
    sym = SYMBOLS[run.bif_param]
    note = (f", {info['partial']} {sym} values stopped at a work limit"
            if info["partial"] else "")
    if info["done"] < info["total"]:
        where = ("spread over the range" if run.bif_sweep == "independent"
                 else "the first direction only")
        return (f"stopped at the time limit ({DIAGRAM_WALL_TIME:g} s): {info['done']} of "
                f"{info['total']} {sym} values, {where}{note}", "partial (time limit)")
    return (f"complete: {what(run)}, {recorded} impacts recorded, {drawn} distinct "
            f"points drawn, in {info['elapsed']:.2f} s{note}", "complete")


class SharedDiagram:
    """One diagram computation, followed by every session that shows it.

    A follower is ``(ticket, on_chunk, on_done, on_error)``: ``on_chunk(part, done,
    total)``, ``on_done(info)`` and ``on_error(text)`` are sent through the ticket (so
    they run on that session's event loop, and not at all once it moved on).
    """

    def __init__(self, run: Run):
        self.run, self.key = run, run.diagram_key()
        self.directions = directions(run)
        values = sweep_values(run)
        # independent: interleaved chunks; continuation: one chain per direction
        self.order = (interleaved(values) if self.directions == (0,)
                      else np.tile(values, len(self.directions)))
        self.parts: list[dict] = []
        self.computed = self.partial = 0
        self.info: dict | None = None        # set when finished
        self.error: str | None = None
        self.abandoned = False               # every follower left before the end
        self.nbytes = 0
        self._followers: list[tuple] = []
        self._lock = threading.RLock()
        self._t0 = time.perf_counter()

    @property
    def finished(self) -> bool:
        return self.info is not None or self.error is not None

    def follow(self, ticket, on_chunk, on_done, on_error) -> None:
        """Send what is there to this follower at once, and the rest as it comes.
        Called with the cache's lock held (see ``DiagramCache.follow``)."""
        follower = (ticket, on_chunk, on_done, on_error)
        with self._lock:          # sends keep their order: replay, then new chunks
            self.abandoned = False
            if self.parts:
                ticket.send(on_chunk, merged(self.parts), self.computed, self.order.size)
            if self.finished:
                self._end(follower)
                return
            self._followers.append(follower)
        ticket.on_cancel(lambda: self._leave(follower))

    def _leave(self, follower) -> None:
        with self._lock:
            if follower in self._followers:
                self._followers.remove(follower)
            if not self._followers and not self.finished:
                self.abandoned = True          # the next chunk task stops here

    def _end(self, follower) -> None:
        ticket, _, on_done, on_error = follower
        if self.error is not None:
            ticket.send(on_error, self.error)
        else:
            ticket.send(on_done, dict(self.info))
        ticket.finish()

    def start(self) -> None:
        _submit(self._step)

    def _step(self) -> None:
        if self.abandoned and CACHE.drop_abandoned(self):
            return
        n = self.order.size
        direction = 0
        if self.directions != (0,):
            size = self.run.bif_n
            direction = self.directions[self.computed // size]
        elif self.computed == 0:
            size = min(FIRST_CHUNK, n)
        else:
            rate = self.computed / max(time.perf_counter() - self._t0, 1e-6)
            size = int(min(max(1, rate * CHUNK_SECONDS), max(1, n // 4), MAX_CHUNK))
        values = self.order[self.computed: self.computed + size]
        try:
            part = compute_chunk(self.run, np.sort(values), direction)
        except Exception as exc:   # report, never kill the worker, no traceback in the log
            log.warning("bifurcation diagram failed: %s: %s", type(exc).__name__, exc)
            part, error = None, f"{type(exc).__name__}: {exc}"
        with self._lock:
            if part is None:
                self.error = error
            else:
                self.partial += part.pop("partial")
                self.computed += values.size
                self.parts.append(part)
                self.nbytes += sum(a.nbytes for a in part.values())
                elapsed = time.perf_counter() - self._t0
                for ticket, on_chunk, _, _ in self._followers:
                    ticket.send(on_chunk, part, self.computed, n)
                if self.computed >= n or elapsed > DIAGRAM_WALL_TIME:
                    self.info = {"elapsed": elapsed, "partial": self.partial,
                                 "done": self.computed, "total": n}
            if self.finished:
                followers, self._followers = self._followers, []
                for f in followers:
                    self._end(f)
        if self.finished:
            CACHE.finished(self)
        else:
            _submit(self._step)


class DiagramCache:
    """Shared diagrams by key: in flight (never evicted) and finished (bounded, LRU)."""

    def __init__(self, max_bytes: int = CACHE_BYTES, max_items: int = CACHE_ITEMS):
        self.max_bytes, self.max_items = max_bytes, max_items
        self._items: OrderedDict[tuple, SharedDiagram] = OrderedDict()
        self._lock = threading.Lock()

    def follow(self, run: Run, ticket, on_chunk, on_done, on_error) -> SharedDiagram:
        """Follow the diagram of ``run``: cached, in flight, or started now."""
        key = run.diagram_key()
        with self._lock:
            shared = self._items.get(key)
            start = shared is None
            if start:
                shared = self._items[key] = SharedDiagram(run)
            self._items.move_to_end(key)
            shared.follow(ticket, on_chunk, on_done, on_error)
        if start:
            shared.start()
        return shared

    def drop_abandoned(self, shared: SharedDiagram) -> bool:
        """Forget a computation nobody follows any more (False: someone came back)."""
        with self._lock, shared._lock:
            if not shared.abandoned:
                return False
            if self._items.get(shared.key) is shared:
                del self._items[shared.key]
            return True

    def finished(self, shared: SharedDiagram) -> None:
        """Keep a complete diagram within the bounds; drop one that is not complete."""
        with self._lock:
            if self._items.get(shared.key) is not shared:
                return
            if shared.error or shared.info["done"] < shared.info["total"]:
                del self._items[shared.key]
            done = [k for k, s in self._items.items() if s.finished]
            size = sum(self._items[k].nbytes for k in done)
            while done and (size > self.max_bytes or len(done) > self.max_items):
                size -= self._items.pop(done.pop(0)).nbytes

    def complete(self, run: Run) -> bool:
        """The diagram of ``run`` is here, finished (following it sends it at once)."""
        with self._lock:
            shared = self._items.get(run.diagram_key())
            return shared is not None and shared.finished and shared.error is None

    def clear(self) -> None:
        with self._lock:
            self._items.clear()

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key) -> bool:
        return key in self._items


CACHE = DiagramCache()


def _submit(fn: Callable[[], None]) -> None:
    try:
        _POOL.submit(fn)
    except RuntimeError:      # interpreter shutting down
        pass


def follow(run: Run, ticket, on_chunk, on_done, on_error) -> SharedDiagram:
    """Show the diagram of ``run`` through ``ticket`` (the work of a session's diagram
    job): from the cache, by following a computation under way, or by starting one."""
    return CACHE.follow(run, ticket, on_chunk, on_done, on_error)
