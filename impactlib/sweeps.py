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
from .flight import RES, system_constants_rows
from .classify import MAX_PERIOD, PERIOD_RTOL, describe, motion_class
from .model import PARAM_NAMES, Params, RunLimits, check_run, fastest_rate, flow_rate
from .simulate import HMAX_PERIODS, METHOD_IDS, run_kernel

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
def sweep_kernel(sps, method, x0s, v0, t_end, t_record, hmaxs, rates, dt, rtol, atol,
                 out_t, out_v, counts, status, finals, classes, classify, warm,
                 max_impacts, max_steps):
    """Run each row of sps in turn from x0s[i] (see run_kernel); results into the out arrays.

    classes[i] = (m, n) codes when classify; finals[i] = (t, x, v, stuck) at the end.
    With warm, value i starts from value i-1's final state, at the time t0 in [0, T_i)
    where the forcing has the phase the previous run ended with.
    """
    nvals = sps.shape[0]
    empty = np.empty(0)
    stick = np.empty((0, 2))
    x, v, t0 = x0s[0], v0, 0.0
    for i in range(nvals):
        sp = sps[i]
        om = sp[5]
        period = 2.0 * math.pi / om
        if not warm:
            x = x0s[i]
        elif i > 0:
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
    lyapunov: np.ndarray | None = None   # per value: largest Lyapunov exponent (lyapunov=True)

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


def _param_rows(p, columns, method, dt, x0):
    """System constants, step caps and rates for each row of parameter ``columns``
    (name -> array of one length).  Every constraint on a single parameter is an
    interval, so checking each column's extremes validates every row."""
    problems = []
    for name, vals in columns.items():
        for v in (vals.min(), vals.max()):
            try:
                p.replace(**{name: float(v)})
            except ValueError as err:
                problems.append(str(err).removeprefix("invalid parameters: "))
    n = len(next(iter(columns.values())))
    full = {f: np.broadcast_to(np.asarray(columns.get(f, getattr(p, f)), dtype=np.float64), (n,))
            for f in PARAM_NAMES}
    if x0 is not None and x0 < full["g"].max():
        problems.append(f"x0={x0!r} is behind the endstop g={full['g'].max()!r}")
    if method == "rk4" and not problems:
        lam = flow_rate(full["m"], full["c"], full["k"])
        worst = int(np.argmax(lam))
        if dt * lam[worst] > 2.78:
            problems.append(f"dt={dt!r} exceeds the RK4 stability limit {2.78 / lam[worst]:.4g} at "
                            + ", ".join(f"{k}={v[worst]!r}" for k, v in columns.items()))
    if problems:
        raise ValueError("invalid sweep values: " + "; ".join(dict.fromkeys(problems)))
    sps = system_constants_rows(*(np.ascontiguousarray(full[f]) for f in PARAM_NAMES))
    rates = fastest_rate(full["m"], full["c"], full["k"], full["omega"])
    hmaxs = np.where(sps[:, RES] != 0.0, 0.25, HMAX_PERIODS) * 2.0 * math.pi / full["omega"]
    return sps, hmaxs, rates


def _run_rows(sps, hmaxs, rates, method, x0s, v0, t_end, t_record, dt, rtol, atol, classify,
              warm, cap, max_impacts, max_steps):
    n = sps.shape[0]
    out_t = np.empty((n, cap))
    out_v = np.empty((n, cap))
    counts = np.zeros(n, dtype=np.int64)
    status = np.zeros(n, dtype=np.int64)
    finals = np.zeros((n, 4))
    classes = np.zeros((n, 2), dtype=np.int64)
    sweep_kernel(sps, METHOD_IDS[method], np.ascontiguousarray(x0s, dtype=np.float64), v0, t_end, t_record, hmaxs, rates,
                 0.0 if dt is None else dt, rtol, atol, out_t, out_v, counts, status, finals,
                 classes, classify, warm, max_impacts, max_steps)
    return out_t, out_v, counts, status, finals, classes


def _split(n, parts):
    edges = np.linspace(0, n, parts + 1).round().astype(int)
    return [(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def _rows(values, order, T_of, out_t, out_v, counts, direction):
    """Row arrays (param, v, t, phase, index, direction) of runs of values[order]."""
    kept = np.minimum(counts, out_t.shape[1])
    idx = np.repeat(np.arange(len(kept)), kept)
    mask = np.arange(out_t.shape[1])[None, :] < kept[:, None]
    t = out_t[mask]
    return (values[order][idx], out_v[mask], t, np.mod(t, T_of[order][idx]), order[idx],
            np.full(idx.shape, direction, dtype=np.int8))


def bifurcation(p: Params, name: str, values, t_end: float = 500.0, t_record: float = 250.0,
                method: str = "exact", *, x0: float | None = None, v0: float = 0.0,
                warm_start: bool | str = False, dt: float | None = None, rtol: float = 1e-6,
                atol: float = 1e-9, workers: int | None = None,
                cap_per_value: int = CAP_PER_VALUE, max_impacts: int = 1_000_000,
                max_steps: int = 20_000_000, lyapunov: bool = False) -> Bifurcation:
    """Impact velocities against one parameter (the paper's Fig. 3).

    Parameters
    ----------
    p : Params
        The fixed parameters; ``name`` takes each of ``values`` in turn.
    name : {"m", "c", "k", "g", "r", "omega"}
    values : array_like
    t_end, t_record : float
        Each run lasts t_end and keeps impacts after t_record.
    x0, v0 : float
        Start of every run (x0 defaults to max(0, g), per value when sweeping g).
    warm_start : False, "up", "down" or "both"
        False: every value starts from (x0, v0) (independent runs, in parallel).
        "up"/"down": values sorted, each run starting where the previous one ended, at the
        same forcing phase (continuation: exposes hysteresis and coexisting attractors);
        "both" runs up and down at once, rows tagged by ``direction``.
    workers : int
        Threads; default all cores (the pool is shared by all callers in the process).
    cap_per_value : int
        Impacts kept per value; more are counted in ``n_impacts`` and flagged (status 3).
    lyapunov : bool
        Also the largest Lyapunov exponent of each value over [t_record, t_end], from the
        same runs (``Bifurcation.lyapunov``; -inf where the motion sticks, NaN where it
        grows without bound; see :mod:`impactlib.lyapunov`).  Exact method only.

    Returns
    -------
    Bifurcation
        Rows sorted by value index (then direction, then time); ``status`` and
        ``n_impacts`` aligned with ``values`` (worst status and total over directions).
    """
    if lyapunov:
        from .lyapunov import bifurcation_with_lyapunov
        return bifurcation_with_lyapunov(p, name, values, t_end, t_record, method, x0, v0,
                                         warm_start, dt, rtol, atol, workers, cap_per_value,
                                         max_impacts, max_steps)
    t_end, t_record, x0c, v0, _, dt, rtol, atol = _check_sweep(
        p, [name], t_end, t_record, x0, v0, method, dt, rtol, atol)
    values = _values_array(name, values)
    if warm_start not in (False, True, "up", "down", "both"):
        raise ValueError(f"warm_start={warm_start!r} must be False, 'up', 'down' or 'both'")
    tic = time.perf_counter()
    ex = _executor(workers)
    n = values.size
    sps, hmaxs, rates = _param_rows(p, {name: values}, method, dt, x0)
    T_of = 2 * math.pi / sps[:, 5]
    if x0 is not None:
        x0s = np.full(n, x0c)
    elif name == "g":
        x0s = np.maximum(0.0, values)
    else:
        x0s = np.full(n, max(0.0, p.g))
    common = dict(method=method, v0=v0, t_end=t_end, t_record=t_record, dt=dt, rtol=rtol,
                  atol=atol, classify=False, cap=cap_per_value, max_impacts=max_impacts,
                  max_steps=max_steps)
    jobs = []
    if warm_start:
        srt = np.argsort(values, kind="stable")
        for d in {"up": [1], True: [1], "down": [-1], "both": [1, -1]}[warm_start]:
            order = srt if d > 0 else srt[::-1]
            jobs.append((d, order, ex.submit(_run_rows, sps[order], hmaxs[order], rates[order],
                                             x0s=x0s[order], warm=True, **common)))
    else:
        # interleaved chunks spread the costly values (chatter) evenly over the threads
        nchunks = min(n, max(4 * (workers or worker_count()), int(math.ceil(n / 128))))
        for j in range(nchunks):
            order = np.arange(j, n, nchunks)
            jobs.append((0, order, ex.submit(_run_rows, sps[order], hmaxs[order], rates[order],
                                             x0s=x0s[order], warm=False, **common)))
    parts = []
    for d, order, fut in jobs:
        out_t, out_v, counts, st, _, _ = fut.result()
        parts.append((order, st, counts, _rows(values, order, T_of, out_t, out_v, counts, d)))
    return merge_parts(name, values, parts, time.perf_counter() - tic)


def merge_parts(name, values, parts, elapsed) -> Bifurcation:
    """One Bifurcation from parts (positions in values, status, n_impacts, row arrays):
    rows sorted by value index, then direction (up first), then time; per-value status the
    worst and n_impacts the total over the parts that ran that value."""
    n = values.size
    status = np.zeros(n, dtype=np.int64)
    n_impacts = np.zeros(n, dtype=np.int64)
    for order, st, counts, _ in parts:
        np.maximum.at(status, order, st)
        np.add.at(n_impacts, order, counts)
    cols = [np.concatenate(c) for c in zip(*(rows for *_, rows in parts))]
    k = np.lexsort((cols[2], -cols[5], cols[4]))
    param, v, t, phase, index, direction = (c[k] for c in cols)
    return Bifurcation(name=name, values=values, param=param, v=v, t=t, phase=phase,
                       index=index, direction=direction, status=status, n_impacts=n_impacts,
                       elapsed=elapsed)


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
    x_start = x0c
    impacts = np.zeros((vy.size, vx.size), dtype=np.int64)
    period = np.zeros_like(impacts)
    status = np.zeros_like(impacts)

    def task(iy0, iy1):
        for iy in range(iy0, iy1):
            sps, hmaxs, rates = _param_rows(p, {name_x: vx, name_y: np.full(vx.size, vy[iy])},
                                            method, dt, x0)
            # each cell starts at x0, or at rest on its own wall (max(0, g))
            x0s = np.full(vx.size, x_start) if x0 is not None else np.maximum(0.0, sps[:, 3])
            _, _, _, st, _, cls = _run_rows(
                sps, hmaxs, rates, method=method, x0s=x0s, v0=v0, t_end=t_end,
                t_record=t_record, dt=dt, rtol=rtol, atol=atol, classify=True, warm=False,
                cap=512, max_impacts=max_impacts, max_steps=max_steps)
            impacts[iy], period[iy], status[iy] = cls[:, 0], cls[:, 1], st

    ex = _executor(workers)
    futs = [ex.submit(task, a, b) for a, b in _split(vy.size, max(1, vy.size // rows_per_task))]
    for f in futs:
        f.result()
    return RegimeMap(name_x, vx, name_y, vy, impacts, period, status, time.perf_counter() - tic)
