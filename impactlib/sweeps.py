"""Parameter sweeps: bifurcation diagrams and two-parameter regime maps.

Each value is an independent run (or, with ``warm_start``, starts from the previous
value's final state at the matching forcing phase).  Runs keep only what the caller
needs: impacts inside the record window, and for regime maps the (m, n) class.  The
work is split into chunks run by a shared thread pool on ``nogil`` kernels, so every core
works and several callers (app sessions) share the cores instead of oversubscribing them.
"""
from __future__ import annotations

import math
import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ._jit import jit
from .flight import NSP
from .classify import MAX_PERIOD, PERIOD_RTOL, describe, motion_class
from .model import PARAM_NAMES, Params, RunLimits, check_run
from .simulate import METHOD_IDS, run_constants, run_kernel

CAP_PER_VALUE = 4096        # impacts kept per value; more are counted, flagged in status
_POOL_LOCK = threading.Lock()
_POOL: ThreadPoolExecutor | None = None


def worker_count() -> int:
    return max(1, int(os.environ.get("IMPACTLIB_WORKERS", os.cpu_count() or 1)))


def _pool() -> ThreadPoolExecutor:
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(max_workers=worker_count(), thread_name_prefix="impactlib")
        return _POOL


class _Inline:
    """Executor stand-in that runs each task at once, in the caller's thread."""

    class _Done:
        def __init__(self, value):
            self._value = value

        def result(self):
            return self._value

    def submit(self, fn, *args, **kwargs):
        return self._Done(fn(*args, **kwargs))


def _executor(workers):
    return _Inline() if workers == 1 else _pool()


@jit
def _section_times(t_lo, t_hi, period):
    n0 = math.ceil(t_lo / period - 1e-12)
    n1 = math.floor(t_hi / period + 1e-12)
    n = max(0, n1 - n0 + 1)
    out = np.empty(n)
    for i in range(n):
        out[i] = (n0 + i) * period
    return out


@jit
def sweep_kernel(sps, method, x0, v0, t_end, t_record, hmaxs, rates, dt, rtol, atol,
                 out_t, out_v, counts, status, finals, classes, classify, warm,
                 max_impacts, max_steps):
    """Run each row of sps in turn (see run_kernel); results into the out arrays.

    classes[i] = (m, n) codes when classify; finals[i] = (t, x, v, stuck) at the end.
    With warm, value i starts from value i-1's final state, at the time t0 in [0, T_i)
    where the forcing has the phase the previous run ended with.
    """
    nvals = sps.shape[0]
    empty = np.empty(0)
    stick = np.empty((0, 2))
    x, v, t0 = x0, v0, 0.0
    for i in range(nvals):
        sp = sps[i]
        om = sp[5]
        period = 2.0 * math.pi / om
        if warm and i > 0:
            x = finals[i - 1, 1]
            v = finals[i - 1, 2]
            ph = sps[i - 1, 5] * finals[i - 1, 0]
            ph = ph - 2.0 * math.pi * math.floor(ph / (2.0 * math.pi))
            t0 = ph / om
        if classify:
            pc_t = _section_times(t0 + t_record, t0 + t_end, period)
        else:
            pc_t = empty
        pc_x = np.full(pc_t.shape[0], np.nan)
        pc_v = np.full(pc_t.shape[0], np.nan)
        st, n_rec, n_tot, n_stick, n_tail, tf, xf, vf, stuck, nsteps = run_kernel(
            sp, method, t0, x, v, t0 + t_end, t0 + t_record, hmaxs[i], rates[i], dt, rtol, atol,
            out_t[i], out_v[i], stick, pc_t, pc_x, pc_v, empty, empty, empty,
            max_impacts, max_steps)
        counts[i] = n_rec
        status[i] = st
        finals[i, 0] = tf
        finals[i, 1] = xf
        finals[i, 2] = vf
        finals[i, 3] = 1.0 if stuck else 0.0
        if classify:
            nk = min(n_rec, out_t.shape[1])
            m, n = motion_class(pc_x, pc_v, out_t[i, :nk], t0 + t_end, period, n_tail,
                                PERIOD_RTOL, MAX_PERIOD)
            classes[i, 0] = m
            classes[i, 1] = n


@dataclass(frozen=True)
class Bifurcation:
    """Impacts of a sweep, one row per recorded impact (aligned 1-D arrays)."""

    name: str
    values: np.ndarray        # the swept values, in the order run
    param: np.ndarray         # row: the value of the swept parameter
    v: np.ndarray             # row: impact velocity (just before impact, <= 0)
    t: np.ndarray             # row: impact time (from the run's own start)
    phase: np.ndarray         # row: impact phase t mod T
    index: np.ndarray         # row: index into values
    direction: np.ndarray     # row: +1 sweep up, -1 sweep down (warm start), 0 independent
    status: np.ndarray        # per value: run status (0 ok, 1/2 work limit, 3 output capped)
    n_impacts: np.ndarray     # per value: impacts in the window (kept or not)
    elapsed: float

    def __len__(self):
        return self.param.shape[0]


@dataclass(frozen=True)
class RegimeMap:
    """(m, n) class of each cell of a two-parameter grid; -1 stands for infinity, -2 for
    undetermined (window too short), 0 impacts for no impact."""

    name_x: str
    values_x: np.ndarray
    name_y: str
    values_y: np.ndarray
    impacts: np.ndarray       # (ny, nx) m codes
    period: np.ndarray        # (ny, nx) n codes
    status: np.ndarray        # (ny, nx)
    elapsed: float

    def label(self, iy: int, ix: int) -> str:
        return describe(int(self.impacts[iy, ix]), int(self.period[iy, ix])).label


def _check_sweep(p, names, t_end, t_record, x0, v0, method, dt, rtol, atol):
    problems = []
    for name in names:
        if name not in PARAM_NAMES:
            problems.append(f"parameter name {name!r} is unknown; expected one of "
                            f"{', '.join(PARAM_NAMES)}")
    if problems:
        raise ValueError("invalid sweep: " + "; ".join(problems))
    return check_run(p, t_end=t_end, t_record=t_record, x0=x0, v0=v0, phase=0.0, method=method,
                     dt=dt, rtol=rtol, atol=atol, dense=0, limits=RunLimits())


def _values_array(name, values):
    try:
        arr = np.asarray(values, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"values of {name!r} must be numbers") from None
    if arr.size == 0:
        raise ValueError(f"values of {name!r} is empty")
    bad = arr[~np.isfinite(arr)]
    if bad.size:
        raise ValueError(f"values of {name!r} hold non-finite entries: {bad[:5].tolist()}")
    return arr


def _param_rows(p, assignments, method, dt, x0):
    """System constants for each parameter assignment (validated), plus step scales."""
    n = len(assignments)
    sps = np.empty((n, NSP))
    hmaxs = np.empty(n)
    rates = np.empty(n)
    problems = []
    for i, changes in enumerate(assignments):
        try:
            q = p.replace(**changes)
        except ValueError as err:
            problems.append(f"{changes}: {err}")
            if len(problems) >= 5:
                break
            continue
        if method == "rk4":
            check_run(q, t_end=1.0, t_record=0.0, x0=None, v0=0.0, phase=0.0, method=method,
                      dt=dt, rtol=1e-6, atol=1e-9, dense=0, limits=RunLimits())
        if x0 is not None and x0 < q.g:
            problems.append(f"{changes}: x0={x0!r} is behind the endstop g={q.g!r}")
        sps[i], rates[i], hmaxs[i] = run_constants(q)
    if problems:
        raise ValueError("invalid sweep values: " + "; ".join(problems))
    return sps, hmaxs, rates


def _run_rows(sps, hmaxs, rates, method, x0, v0, t_end, t_record, dt, rtol, atol, classify,
              warm, cap, max_impacts, max_steps):
    n = sps.shape[0]
    out_t = np.empty((n, cap))
    out_v = np.empty((n, cap))
    counts = np.zeros(n, dtype=np.int64)
    status = np.zeros(n, dtype=np.int64)
    finals = np.zeros((n, 4))
    classes = np.zeros((n, 2), dtype=np.int64)
    sweep_kernel(sps, METHOD_IDS[method], x0, v0, t_end, t_record, hmaxs, rates,
                 0.0 if dt is None else dt, rtol, atol, out_t, out_v, counts, status, finals,
                 classes, classify, warm, max_impacts, max_steps)
    return out_t, out_v, counts, status, finals, classes


def _split(n, parts):
    edges = np.linspace(0, n, parts + 1).round().astype(int)
    return [(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def _collect(name, values, order, T_of, out_t, out_v, counts, status, direction, elapsed):
    kept = np.minimum(counts, out_t.shape[1])
    idx = np.repeat(np.arange(len(kept)), kept)
    mask = np.arange(out_t.shape[1])[None, :] < kept[:, None]
    t = out_t[mask]
    periods = T_of[idx]
    return Bifurcation(name=name, values=values, param=values[order][idx], v=out_v[mask], t=t,
                       phase=np.mod(t, periods), index=order[idx],
                       direction=np.full(idx.shape, direction, dtype=np.int8),
                       status=status, n_impacts=counts, elapsed=elapsed)


def bifurcation(p: Params, name: str, values, t_end: float = 500.0, t_record: float = 250.0,
                method: str = "exact", *, x0: float | None = None, v0: float = 0.0,
                warm_start: bool | str = False, dt: float | None = None, rtol: float = 1e-6,
                atol: float = 1e-9, workers: int | None = None,
                cap_per_value: int = CAP_PER_VALUE, max_impacts: int = 1_000_000,
                max_steps: int = 20_000_000) -> Bifurcation:
    """Impact velocities against one parameter (the paper's Fig. 3).

    Parameters
    ----------
    p : Params
        The fixed parameters; ``name`` takes each of ``values`` in turn.
    name : {"m", "c", "k", "g", "r", "omega"}
    values : array_like
    t_end, t_record : float
        Each run lasts t_end and keeps impacts after t_record.
    warm_start : False, "up", "down" or "both"
        False: every value starts from (x0, v0) at rest (independent, run in parallel).
        "up"/"down": values sorted, each starting where the previous ended (continuation,
        exposes hysteresis); "both" runs up and down, rows tagged by ``direction``.
    workers : int
        Threads; default all cores.

    Returns
    -------
    Bifurcation
    """
    t_end, t_record, x0c, v0, _, dt, rtol, atol = _check_sweep(
        p, [name], t_end, t_record, x0, v0, method, dt, rtol, atol)
    values = _values_array(name, values)
    if warm_start not in (False, True, "up", "down", "both"):
        raise ValueError(f"warm_start={warm_start!r} must be False, 'up', 'down' or 'both'")
    x_start = max(0.0, p.g) if x0 is None else x0c
    tic = time.perf_counter()
    ex = _executor(workers)
    sps, hmaxs, rates = _param_rows(p, [{name: v} for v in values], method, dt, x0)
    T_of = 2 * math.pi / sps[:, 5]
    common = dict(method=method, v0=v0, t_end=t_end, t_record=t_record, dt=dt, rtol=rtol,
                  atol=atol, classify=False, cap=cap_per_value, max_impacts=max_impacts,
                  max_steps=max_steps)
    if warm_start:
        directions = {"up": [1], True: [1], "down": [-1], "both": [1, -1]}[warm_start]
        srt = np.argsort(values, kind="stable")
        jobs = []
        for d in directions:
            order = srt if d > 0 else srt[::-1]
            x_first = x_start if x0 is not None or name != "g" else max(0.0, values[order[0]])
            jobs.append((d, order, ex.submit(
                _run_rows, sps[order], hmaxs[order], rates[order], x0=x_first, warm=True,
                **common)))
        parts = []
        for d, order, fut in jobs:
            out_t, out_v, counts, status, _, _ = fut.result()
            parts.append(_collect(name, values, order, T_of[order], out_t, out_v, counts, status,
                                  d, 0.0))
        elapsed = time.perf_counter() - tic
        return _concat(name, values, parts, elapsed)
    order = np.arange(values.size)
    nw = workers or worker_count()
    chunks = _split(values.size, max(nw, int(math.ceil(values.size / 256))))
    futs = []
    for a, b in chunks:
        sl = slice(a, b)
        if name == "g" and x0 is None:
            # each wall position starts at rest on its own wall (or at 0 for a gap)
            futs.append([ex.submit(_run_rows, sps[i:i + 1], hmaxs[i:i + 1], rates[i:i + 1],
                                        x0=max(0.0, values[i]), warm=False, **common)
                         for i in range(a, b)])
        else:
            futs.append([ex.submit(_run_rows, sps[sl], hmaxs[sl], rates[sl], x0=x_start,
                                        warm=False, **common)])
    parts = []
    for (a, b), fl in zip(chunks, futs):
        res = [f.result() for f in fl]
        out_t = np.concatenate([r[0] for r in res])
        out_v = np.concatenate([r[1] for r in res])
        counts = np.concatenate([r[2] for r in res])
        status = np.concatenate([r[3] for r in res])
        parts.append(_collect(name, values, order[a:b], T_of[a:b], out_t, out_v, counts, status,
                              0, 0.0))
    return _concat(name, values, parts, time.perf_counter() - tic)


def _concat(name, values, parts, elapsed):
    cat = lambda f: np.concatenate([getattr(b, f) for b in parts])  # noqa: E731
    return Bifurcation(name=name, values=values, param=cat("param"), v=cat("v"), t=cat("t"),
                       phase=cat("phase"), index=cat("index"), direction=cat("direction"),
                       status=cat("status"), n_impacts=cat("n_impacts"), elapsed=elapsed)


def iter_bifurcation(p: Params, name: str, values, chunk: int = 64, **kwargs):
    """Yield the Bifurcation of successive chunks of ``values`` (for streaming).

    Independent starts only; stop iterating to cancel (no work is queued ahead).
    """
    if kwargs.get("warm_start"):
        raise ValueError("iter_bifurcation streams independent starts; use bifurcation() "
                         "for warm_start")
    values = _values_array(name, values)
    for a in range(0, values.size, chunk):
        yield bifurcation(p, name, values[a:a + chunk], **kwargs)


def regime_map(p: Params, name_x: str, values_x, name_y: str, values_y,
               t_end: float = 500.0, t_record: float = 250.0, method: str = "exact", *,
               x0: float | None = None, v0: float = 0.0, dt: float | None = None,
               rtol: float = 1e-6, atol: float = 1e-9, workers: int | None = None,
               rows_per_task: int = 4, max_impacts: int = 1_000_000,
               max_steps: int = 20_000_000) -> RegimeMap:
    """The (m, n) class on a grid of two parameters, e.g. (omega, r): a picture of where
    the paper's Fig. 3 panels sit.  Memory: one task's impacts at a time per worker."""
    t_end, t_record, x0c, v0, _, dt, rtol, atol = _check_sweep(
        p, [name_x, name_y], t_end, t_record, x0, v0, method, dt, rtol, atol)
    if name_x == name_y:
        raise ValueError(f"name_x and name_y are both {name_x!r}")
    vx = _values_array(name_x, values_x)
    vy = _values_array(name_y, values_y)
    tic = time.perf_counter()
    x_start = max(0.0, p.g) if x0 is None else x0c
    impacts = np.zeros((vy.size, vx.size), dtype=np.int64)
    period = np.zeros_like(impacts)
    status = np.zeros_like(impacts)

    def task(iy0, iy1):
        for iy in range(iy0, iy1):
            sps, hmaxs, rates = _param_rows(p, [{name_x: a, name_y: vy[iy]} for a in vx],
                                            method, dt, x0)
            xs = x_start
            if x0 is None and "g" in (name_x, name_y):
                xs = max(0.0, vy[iy]) if name_y == "g" else max(0.0, float(np.max(vx)))
            _, _, _, st, _, cls = _run_rows(
                sps, hmaxs, rates, method=method, x0=xs, v0=v0, t_end=t_end,
                t_record=t_record, dt=dt, rtol=rtol, atol=atol, classify=True, warm=False,
                cap=512, max_impacts=max_impacts, max_steps=max_steps)
            impacts[iy], period[iy], status[iy] = cls[:, 0], cls[:, 1], st

    ex = _executor(workers)
    futs = [ex.submit(task, a, b) for a, b in _split(vy.size, max(1, vy.size // rows_per_task))]
    for f in futs:
        f.result()
    return RegimeMap(name_x, vx, name_y, vy, impacts, period, status, time.perf_counter() - tic)
