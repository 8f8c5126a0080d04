"""Parameter sweeps: bifurcation diagrams and two-parameter regime maps.

Each value is an independent run (or, with ``warm_start``, starts from the previous
value's final state at the matching forcing phase).  Runs keep only what the caller
needs: impacts inside the record window, and for regime maps the (m, n) class.  Every
sweep of independent starts goes through :func:`run_jobs`: a shared thread pool runs
``nogil`` kernels on blocks of jobs handed out dynamically, so every core works to the
end and several callers (app sessions) share the cores instead of oversubscribing them.
"""
from __future__ import annotations

import math
import time
import dataclasses
from dataclasses import dataclass

import numpy as np

from ..kernels._jit import jit
from ..analysis.classify import MAX_PERIOD, PERIOD_RTOL, Motion, describe, motion_class
from ..analysis.lyapunov import grows_without_bound
from ..kernels.events import step_caps
from ..kernels.flight import G, OM, system_constants_rows
from ..model import (PARAM_NAMES, Params, RunLimits, RunStatus, check_run, fastest_rate,
                     rk4_stability_limits)
from ..kernels import engine as E
from ..kernels.engine import METHOD_IDS, Buffers
from ..parallel import executor as _executor
from ..parallel import interleaved, run_blocks, worker_count
from ..progress import reporter, stopped
from ..kernels.entry import section_times
from ..io.result import SweepResult
from .verdicts import judge_aperiodic

CAP_PER_VALUE = 4096        # impacts kept per value; more are counted, flagged in status


@jit
def sweep_kernel(sps, method, x0s, v0, t_end, t_record, hmaxs, rates, dt, rtol, atol,
                 out_t, out_v, counts, status, finals, classes, classify, warm,
                 max_impacts, max_steps):
    """Run each row of sps in turn from (x0s[i], v0) (see engine.run_engine); results into the
    out arrays.  :func:`rows_kernel` with one start velocity for all rows."""
    rows_kernel(sps, method, x0s, np.full(sps.shape[0], v0), t_end, t_record, hmaxs, rates,
                dt, rtol, atol, out_t, out_v, counts, status, finals, classes, classify, warm,
                max_impacts, max_steps)


@jit
def rows_kernel(sps, method, x0s, v0s, t_end, t_record, hmaxs, rates, dt, rtol, atol,
                out_t, out_v, counts, status, finals, classes, classify, warm,
                max_impacts, max_steps):
    """Run each row of sps in turn from (x0s[i], v0s[i]) (see engine.run_engine); results into
    the out arrays.

    classes[i] = (m, n) codes when classify; finals[i] = (t, x, v, stuck, impacts in all,
    steps) at the end.
    With warm, value i starts from value i-1's final state, at the time t0 in [0, T_i)
    where the forcing has the phase the previous run ended with.
    """
    nvals = sps.shape[0]
    empty = np.empty(0)
    stick = np.empty((0, 2))
    res = np.empty(E.NRES)
    x, v, t0 = x0s[0], v0s[0], 0.0
    for i in range(nvals):
        sp = sps[i]
        om = sp[OM]
        period = 2.0 * math.pi / om
        if not warm:
            x = x0s[i]
            v = v0s[i]
        elif i > 0:
            x = finals[i - 1, 1]
            v = finals[i - 1, 2]
            ph = sps[i - 1, OM] * finals[i - 1, 0]
            ph = ph - 2.0 * math.pi * math.floor(ph / (2.0 * math.pi))
            t0 = ph / om
        if classify:
            pc_t = section_times(t0 + t_record, t0 + t_end, 0.0, period)
        else:
            pc_t = empty
        pc_x = np.full(pc_t.shape[0], np.nan)
        pc_v = np.full(pc_t.shape[0], np.nan)
        ctl = E.controls(t0 + t_end, t0 + t_record, hmaxs[i], rates[i], dt, rtol, atol,
                         max_impacts, max_steps, method, E.NO_TANGENT)
        buf = Buffers(out_t[i], out_v[i], stick, pc_t, pc_x, pc_v, empty, empty, empty, empty,
                      stick)
        st = E.run_engine(sp, ctl, t0, x, v, buf, res)
        n_rec = int(res[E.N_REC])
        n_tail = int(res[E.N_TAIL])
        counts[i] = n_rec
        status[i] = st
        finals[i, 0] = res[E.T_F]
        finals[i, 1] = res[E.X_F]
        finals[i, 2] = res[E.V_F]
        finals[i, 3] = res[E.STUCK]
        finals[i, 4] = res[E.N_TOT]
        finals[i, 5] = res[E.NSTEPS]
        if classify:
            nk = min(n_rec, out_t.shape[1])
            m, n = motion_class(pc_x, pc_v, out_t[i, :nk], t0 + t_end, period, n_tail,
                                PERIOD_RTOL, MAX_PERIOD)
            classes[i, 0] = m
            classes[i, 1] = n


@dataclass(frozen=True, repr=False, eq=False)
class Bifurcation(SweepResult):
    """Impacts of a sweep, one row per recorded impact (aligned 1-D arrays).

    Attributes
    ----------
    name : str
        The swept parameter.
    values : ndarray, shape (N,)
        The swept values, in the order given (units of ``name``).
    param, v, t, phase, index, direction : ndarray, shape (R,)
        One row per recorded impact: the swept value, the velocity just before impact
        (<= 0), the impact time from its run's start (s), t mod T (s), the index into
        ``values``, and +1 / -1 for a warm-started sweep up / down (0 independent).
    status : ndarray of int, shape (N,)
        Per value: 0 ok, 1 impact limit, 2 step limit, 3 more impacts than kept.
    n_impacts : ndarray of int, shape (N,)
        Per value: impacts in the record window, kept or not.
    elapsed : float
        Seconds (not part of ``==``).
    lyapunov : ndarray, shape (N,) or None
        Per value: largest Lyapunov exponent (1/s) with ``lyapunov=True``.
    params : Params or None
        The fixed parameters (``name`` takes each value in turn).
    options : dict
        The run settings: t_end, t_record, method, x0, v0, warm_start, ...
    """

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
    params: Params | None = None
    options: dict = dataclasses.field(default_factory=dict)

    def __len__(self):
        return self.param.shape[0]


@dataclass(frozen=True, repr=False, eq=False)
class RegimeMap(SweepResult):
    """(m, n) class of each cell of a two-parameter grid: counts, 0 impacts for no
    impact, or the codes of :class:`impactlib.model.MotionCode` (INFINITE -1,
    UNDETERMINED -2, NOT_SETTLED -3, UNBOUNDED -4).

    ``values_x`` (nx,) and ``values_y`` (ny,) are the grid of ``name_x`` and ``name_y``;
    ``impacts`` (m), ``period`` (n) and ``status`` (as in :class:`Bifurcation`) are
    (ny, nx) integer arrays, row iy and column ix for (values_y[iy], values_x[ix]);
    ``elapsed`` seconds (not part of ``==``); ``params`` the fixed parameters and
    ``options`` the run settings (t_end, t_record, method, x0, v0, ...).

    Cells whose section points never repeat are judged by :func:`classify` on their own
    run (the Lyapunov criterion): ``motions[(iy, ix)]`` holds its verdict, and their codes
    become (m, INFINITE) chaotic, (NOT_SETTLED, INFINITE), (UNDETERMINED, UNDETERMINED)
    or (UNBOUNDED, INFINITE).  :meth:`motion` and :meth:`label` read both.
    """

    name_x: str
    values_x: np.ndarray
    name_y: str
    values_y: np.ndarray
    impacts: np.ndarray       # (ny, nx) m codes
    period: np.ndarray        # (ny, nx) n codes
    status: np.ndarray        # (ny, nx)
    elapsed: float
    motions: dict = dataclasses.field(default_factory=dict)   # (iy, ix) -> classify's Motion
    params: Params | None = None
    options: dict = dataclasses.field(default_factory=dict)

    def motion(self, iy: int, ix: int) -> Motion:
        got = self.motions.get((int(iy), int(ix)))
        return got if got is not None else describe(int(self.impacts[iy, ix]),
                                                    int(self.period[iy, ix]))

    def label(self, iy: int, ix: int) -> str:
        return self.motion(iy, ix).label


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
        lims = rk4_stability_limits(full["m"], full["c"], full["k"])
        worst = int(np.argmin(lims))
        if dt > lims[worst]:
            problems.append(f"dt={dt!r} exceeds the RK4 stability limit {lims[worst]:.4g} at "
                            + ", ".join(f"{k}={v[worst]!r}" for k, v in columns.items()))
    if problems:
        raise ValueError("invalid sweep values: " + "; ".join(dict.fromkeys(problems)))
    sps = system_constants_rows(*(np.ascontiguousarray(full[f]) for f in PARAM_NAMES))
    rates = fastest_rate(full["m"], full["c"], full["k"], full["omega"])
    hmaxs = step_caps(sps)
    return sps, hmaxs, rates


def _run_rows(sps, hmaxs, rates, method, x0s, v0, t_end, t_record, dt, rtol, atol, classify,
              warm, cap, max_impacts, max_steps):
    """rows_kernel on fresh output arrays; v0 is one start velocity or one per row."""
    n = sps.shape[0]
    out_t = np.empty((n, cap))
    out_v = np.empty((n, cap))
    counts = np.zeros(n, dtype=np.int64)
    status = np.zeros(n, dtype=np.int64)
    finals = np.zeros((n, 6))
    classes = np.zeros((n, 2), dtype=np.int64)
    v0s = np.ascontiguousarray(np.broadcast_to(np.asarray(v0, dtype=np.float64), (n,)))
    rows_kernel(sps, METHOD_IDS[method], np.ascontiguousarray(x0s, dtype=np.float64), v0s,
                t_end, t_record, hmaxs, rates, 0.0 if dt is None else dt, rtol, atol, out_t,
                out_v, counts, status, finals, classes, classify, warm, max_impacts, max_steps)
    return out_t, out_v, counts, status, finals, classes


#: output held by one block of jobs (impacts kept x jobs): bounds a block's size
BLOCK_OUTPUT = 1 << 18


def run_jobs(sps, hmaxs, rates, x0s, v0s, *, method, t_end, t_record, dt, rtol, atol,
             classify, cap, max_impacts, max_steps, on_block, workers=None, cancel=None,
             order=None) -> int:
    """Run N independent jobs on the shared thread pool: balanced, streaming, cancellable.

    Job i is one run (see :func:`rows_kernel`) of the system constants ``sps[i]`` (with
    ``hmaxs[i]``, ``rates[i]`` from :func:`_param_rows`) from x = x0s[i], v = v0s[i] at
    t = 0; the other settings are shared.  This is the entry for any sweep of independent
    starts (diagrams, regime maps, basin grids).

    Balanced: ``workers`` threads (default: the pool's size) each take the next block of
    jobs, in ``order`` (default :func:`interleaved`), from a shared counter; blocks
    shrink as the jobs run out (guided self-scheduling: a quarter of the remaining jobs
    per worker, at most BLOCK_OUTPUT / cap jobs so a block's output stays small), so no
    thread idles while another holds a costly stretch.
    Streaming: ``on_block(idx, out_t, out_v, counts, status, finals, classes)`` is called
    in the worker's thread as each block ends, ``idx`` the block's job indices and the
    arrays the block's results (as :func:`_run_rows`; out_t holds each job's recorded
    impacts, ``cap`` at most).
    Cancellable: once ``cancel`` (a threading.Event) is set, no block is handed out;
    blocks under way finish.

    Returns the number of jobs run.  With ``workers=1`` the jobs run in the caller's thread.
    """
    n = sps.shape[0]
    order = interleaved(n) if order is None else np.asarray(order)

    def run_block(idx):
        res = _run_rows(sps[idx], hmaxs[idx], rates[idx], method=method, x0s=x0s[idx],
                        v0=v0s[idx], t_end=t_end, t_record=t_record, dt=dt, rtol=rtol,
                        atol=atol, classify=classify, warm=False, cap=cap,
                        max_impacts=max_impacts, max_steps=max_steps)
        on_block(idx, *res)

    return run_blocks(n, run_block, order=order, max_block=max(1, BLOCK_OUTPUT // max(1, cap)),
                      workers=workers, cancel=cancel)


def _rows(values, order, T_of, out_t, out_v, counts, direction):
    """Row arrays (param, v, t, phase, index, direction) of runs of values[order]."""
    kept = np.minimum(counts, out_t.shape[1])
    m = int(kept.sum())
    return _gather_rows(values, np.asarray(order, dtype=np.int64), T_of, out_t, out_v, kept,
                        m, direction)


@jit
def _gather_rows(values, order, T_of, out_t, out_v, kept, m, direction):
    # one pass over the kept prefix of each run's row of out_t, off the GIL: a sweep's
    # threads build their blocks' rows at once (numpy's dozen calls per block held it)
    param, v, t = np.empty(m), np.empty(m), np.empty(m)
    phase, index = np.empty(m), np.empty(m, dtype=np.int64)
    dirs = np.full(m, direction, dtype=np.int8)
    j = 0
    for i in range(kept.shape[0]):
        o = order[i]
        for c in range(kept[i]):
            ti = out_t[i, c]
            param[j], v[j], t[j], index[j] = values[o], out_v[i, c], ti, o
            phase[j] = np.mod(ti, T_of[o])
            j += 1
    return param, v, t, phase, index, dirs


def bifurcation(p: Params, name: str, values, t_end: float = 500.0, t_record: float = 250.0,
                method: str = "exact", *, x0: float | None = None, v0: float = 0.0,
                warm_start: bool | str = False, dt: float | None = None, rtol: float = 1e-6,
                atol: float = 1e-9, workers: int | None = None,
                cap_per_value: int = CAP_PER_VALUE, max_impacts: int = 1_000_000,
                max_steps: int = 20_000_000, lyapunov: bool = False, progress=None,
                cancel=None) -> Bifurcation:
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
    progress : True or callable, optional
        A tqdm bar (True) or ``progress(done, total)`` after each chunk of values.
    cancel : threading.Event, optional
        Once set, no further chunk starts; the result holds the values done.
        (With either, the sweep runs in chunks: :func:`_bifurcation_in_chunks`.)

    Returns
    -------
    Bifurcation
        Rows sorted by value index (then direction, then time); ``status`` and
        ``n_impacts`` aligned with ``values`` (worst status and total over directions).
    """
    if progress is not None or cancel is not None:
        return _bifurcation_in_chunks(p, name, values, t_end, t_record, method, x0=x0, v0=v0,
                       warm_start=warm_start, dt=dt, rtol=rtol, atol=atol, workers=workers,
                       cap_per_value=cap_per_value, max_impacts=max_impacts,
                       max_steps=max_steps, lyapunov=lyapunov, progress=progress, cancel=cancel)
    if lyapunov:
        return bifurcation_with_lyapunov(p, name, values, t_end, t_record, method, x0, v0,
                                         warm_start, dt, rtol, atol, workers, cap_per_value,
                                         max_impacts, max_steps)
    t_end, t_record, x0c, v0, _, dt, rtol, atol = _check_sweep(
        p, [name], t_end, t_record, x0, v0, method, dt, rtol, atol)
    values = _values_array(name, values)
    if warm_start not in (False, True, "up", "down", "both"):
        raise ValueError(f"warm_start={warm_start!r} must be False, 'up', 'down' or 'both'")
    tic = time.perf_counter()
    n = values.size
    sps, hmaxs, rates = _param_rows(p, {name: values}, method, dt, x0)
    T_of = 2 * math.pi / sps[:, OM]
    if x0 is not None:
        x0s = np.full(n, x0c)
    elif name == "g":
        x0s = np.maximum(0.0, values)
    else:
        x0s = np.full(n, max(0.0, p.g))
    common = dict(method=method, t_end=t_end, t_record=t_record, dt=dt, rtol=rtol,
                  atol=atol, classify=False, cap=cap_per_value, max_impacts=max_impacts,
                  max_steps=max_steps)
    parts = []
    if warm_start:
        srt = np.argsort(values, kind="stable")
        jobs = []
        for d in {"up": [1], True: [1], "down": [-1], "both": [1, -1]}[warm_start]:
            order = srt if d > 0 else srt[::-1]
            run = (lambda order=order: _run_rows(sps[order], hmaxs[order], rates[order],
                                                 x0s=x0s[order], v0=v0, warm=True, **common))
            jobs.append((d, order, _executor(workers).submit(run)))
        for d, order, fut in jobs:
            out_t, out_v, counts, st, _, _ = fut.result()
            parts.append((order, st, counts, _rows(values, order, T_of, out_t, out_v, counts, d)))
    else:
        def collect(idx, out_t, out_v, counts, st, finals, classes):
            parts.append((idx, st, counts, _rows(values, idx, T_of, out_t, out_v, counts, 0)))

        run_jobs(sps, hmaxs, rates, x0s, np.full(n, v0), on_block=collect, workers=workers,
                 **common)
    return dataclasses.replace(
        merge_parts(name, values, parts, time.perf_counter() - tic), params=p,
        options=sweep_options(t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0,
                              warm_start=warm_start, dt=dt, rtol=rtol, atol=atol))


def sweep_options(**kw) -> dict:
    """The settings a sweep records (its ``options``): the step or the tolerances only
    for the method that uses them."""
    if kw.get("method") != "rk4":
        kw.pop("dt", None)
    if kw.get("method") != "rk45":
        kw.pop("rtol", None)
        kw.pop("atol", None)
    return kw


def row_order(index, direction, t) -> np.ndarray:
    """The order of rows by value index, then direction (up first), then time, i.e.
    ``np.lexsort((t, -direction, index))``. Each run's rows arrive together and in time
    order, so only the runs are sorted (a few thousand keys where the rows are 10^5: the
    lexsort of all rows was most of a diagram's serial time); rows that do not arrive
    so are sorted in full."""
    m = index.size
    if m == 0:
        return np.zeros(0, dtype=np.int64)
    starts = np.flatnonzero(np.r_[True, (index[1:] != index[:-1])
                                  | (direction[1:] != direction[:-1])])
    lengths = np.diff(np.r_[starts, m])
    within = np.ones(m, dtype=bool)
    within[starts] = False
    if np.any(t[1:][within[1:]] < t[:-1][within[1:]]):
        return np.lexsort((t, -direction, index))
    runs = np.lexsort((-direction[starts], index[starts]))
    if np.unique(index[starts] * 3 + direction[starts]).size < starts.size:
        return np.lexsort((t, -direction, index))     # one run's rows in two places
    first = np.cumsum(np.r_[0, lengths[runs][:-1]])
    return np.repeat(starts[runs] - first, lengths[runs]) + np.arange(m)


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
    k = row_order(cols[4], cols[5], cols[2])
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
               max_steps: int = 20_000_000, progress=None, cancel=None) -> RegimeMap:
    """The (m, n) class on a grid of two parameters, e.g. (omega, r): a picture of where
    the paper's Fig. 3 panels sit.

    Every cell is one job of :func:`run_jobs` (cells handed out to the workers in small
    blocks; ``rows_per_task`` is accepted for compatibility and not used).  Memory: one
    block's impacts at a time per worker.  ``progress`` (True for a tqdm bar, or
    ``progress(rows_done, rows)``) and ``cancel`` (a threading.Event) run it in blocks of
    rows: :func:`_regime_map_in_blocks`."""
    if progress is not None or cancel is not None:
        return _regime_map_in_blocks(p, name_x, values_x, name_y, values_y, t_end, t_record, method, x0=x0,
                       v0=v0, dt=dt, rtol=rtol, atol=atol, workers=workers,
                       max_impacts=max_impacts, max_steps=max_steps, progress=progress,
                       cancel=cancel)
    t_end, t_record, x0c, v0, _, dt, rtol, atol = _check_sweep(
        p, [name_x, name_y], t_end, t_record, x0, v0, method, dt, rtol, atol)
    if name_x == name_y:
        raise ValueError(f"name_x and name_y are both {name_x!r}")
    vx = _values_array(name_x, values_x)
    vy = _values_array(name_y, values_y)
    tic = time.perf_counter()
    nx, ny = vx.size, vy.size
    # every cell is one job: (iy, ix) -> iy * nx + ix
    sps, hmaxs, rates = _param_rows(p, {name_x: np.tile(vx, ny), name_y: np.repeat(vy, nx)},
                                    method, dt, x0)
    # each cell starts at x0, or at rest on its own wall (max(0, g))
    x0s = np.full(nx * ny, x0c) if x0 is not None else np.maximum(0.0, sps[:, G])
    impacts = np.zeros(ny * nx, dtype=np.int64)
    period = np.zeros_like(impacts)
    status = np.zeros_like(impacts)
    finals = np.zeros((ny * nx, 6))

    def collect(idx, out_t, out_v, counts, st, fin, classes):
        impacts[idx], period[idx], status[idx] = classes[:, 0], classes[:, 1], st
        finals[idx] = fin

    run_jobs(sps, hmaxs, rates, x0s, np.full(nx * ny, v0), method=method, t_end=t_end,
             t_record=t_record, dt=dt, rtol=rtol, atol=atol, classify=True, cap=512,
             max_impacts=max_impacts, max_steps=max_steps, on_block=collect, workers=workers)
    impacts, period, status = (a.reshape(ny, nx) for a in (impacts, period, status))
    motions = judge_aperiodic(p, name_x, vx, name_y, vy, impacts, period, finals, workers,
                              t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0,
                              dt=dt, rtol=rtol, atol=atol, max_impacts=max_impacts,
                              max_steps=max_steps)
    return RegimeMap(name_x, vx, name_y, vy, impacts, period, status, time.perf_counter() - tic,
                     motions, params=p,
                     options=sweep_options(t_end=t_end, t_record=t_record, method=method,
                                           x0=x0, v0=v0, dt=dt, rtol=rtol, atol=atol))


# ------------------------------------------------------------------ the Lyapunov sweep


@jit
def lyapunov_sweep_kernel(sps, x0s, v0, t_end, t_record, hmaxs, rates, out_t, out_v, counts,
                          status, finals, lyap, warm, max_impacts, max_steps):
    """sweep_kernel (exact method, no classification) with the tangent carried
    along by the engine: lyap[i] = (sum log|R11|, sum log|R22|, stuck in window, impacts in window)
    of value i over its window [t0 + t_record, t0 + t_end] (the sums from the leading
    column, engine.LEADING)."""
    nvals = sps.shape[0]
    marks = np.empty(2)
    logs = np.zeros((1, 2))
    res = np.empty(E.NRES)
    none = np.empty(0)
    stick = np.empty((0, 2))
    x, v, t0 = x0s[0], v0, 0.0
    for i in range(nvals):
        sp = sps[i]
        om = sp[5]
        if not warm:
            x = x0s[i]
        elif i > 0:
            x = finals[i - 1, 1]
            v = finals[i - 1, 2]
            ph = sps[i - 1, 5] * finals[i - 1, 0]
            ph = ph - 2.0 * math.pi * math.floor(ph / (2.0 * math.pi))
            t0 = ph / om
        marks[0] = t0 + t_record
        marks[1] = t0 + t_end
        logs[0, 0] = 0.0
        logs[0, 1] = 0.0
        ctl = E.controls(t0 + t_end, t0 + t_record, hmaxs[i], rates[i], 0.0, 0.0, 0.0,
                         max_impacts, max_steps, E.EXACT, E.LEADING)
        buf = Buffers(out_t[i], out_v[i], stick, none, none, none, none, none, none, marks,
                      logs)
        st = E.run_engine(sp, ctl, t0, x, v, buf, res)
        counts[i] = int(res[E.N_REC])
        status[i] = st
        finals[i, 0] = res[E.T_F]
        finals[i, 1] = res[E.X_F]
        finals[i, 2] = res[E.V_F]
        finals[i, 3] = res[E.STUCK]
        lyap[i, 0] = logs[0, 0]
        lyap[i, 1] = logs[0, 1]
        lyap[i, 2] = res[E.STUCK_MARKED]
        lyap[i, 3] = res[E.N_MARKED]


def largest_exponents(sps_c, sps_r, lyap, status, tau, out_t, out_v, counts, t_lo, t_hi):
    """The largest exponent per value from the sweep kernel's sums: -inf where the motion
    sticks in the window, NaN where it grows without bound or stopped at a work limit."""
    lam = np.maximum(lyap[:, 0], lyap[:, 1]) / tau
    lam = np.where(lyap[:, 2] > 0, -math.inf, lam)
    lam = np.where(status == RunStatus.IMPACT_LIMIT, math.nan, lam)
    lam = np.where(status == RunStatus.STEP_LIMIT, math.nan, lam)
    for i in np.flatnonzero((sps_c == 0.0) & (sps_r == 1.0)):
        k = min(counts[i], out_t.shape[1])
        if grows_without_bound(out_t[i, :k], out_v[i, :k], t_lo[i], t_hi[i]):
            lam[i] = math.nan
    return lam


def bifurcation_with_lyapunov(p, name, values, t_end, t_record, method, x0, v0, warm_start,
                              dt, rtol, atol, workers, cap_per_value, max_impacts, max_steps):
    """:func:`impactlib.bifurcation` with ``lyapunov=True``: the same runs (the exact
    kernels, the same scheduling) with the tangent carried along, so the diagram's rows
    come with the largest exponent of each value over the diagram's own window."""
    if method != "exact":
        raise ValueError(f"lyapunov=True needs method='exact' (got method={method!r}): the "
                         "exponents come from the exact flow and saltation Jacobians")
    t_end, t_record, x0c, v0, _, dt, rtol, atol = _check_sweep(
        p, [name], t_end, t_record, x0, v0, method, dt, rtol, atol)
    values = _values_array(name, values)
    if warm_start not in (False, True, "up", "down", "both"):
        raise ValueError(f"warm_start={warm_start!r} must be False, 'up', 'down' or 'both'")
    if not t_record < t_end:
        raise ValueError(f"invalid sweep: t_record={t_record!r} must be < t_end={t_end!r} "
                         "for Lyapunov exponents over [t_record, t_end]")
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

    def run(order, warm):
        k = order.size
        out_t = np.empty((k, cap_per_value))
        out_v = np.empty((k, cap_per_value))
        counts = np.zeros(k, dtype=np.int64)
        status = np.zeros(k, dtype=np.int64)
        finals = np.zeros((k, 4))
        lyap = np.zeros((k, 4))
        lyapunov_sweep_kernel(sps[order], np.ascontiguousarray(x0s[order]), v0, t_end, t_record,
                              hmaxs[order], rates[order], out_t, out_v, counts, status, finals,
                              lyap, warm, max_impacts, max_steps)
        status = np.where((status == RunStatus.OK) & (counts > cap_per_value),
                          RunStatus.OUTPUT_FULL, status)
        t0 = finals[:, 0] - t_end
        lam = largest_exponents(sps[order, 1], sps[order, 4], lyap, status, t_end - t_record,
                                out_t, out_v, counts, t0 + t_record, t0 + t_end)
        return out_t, out_v, counts, status, lam

    done = []         # (direction, order, results of run(order))
    if warm_start:
        srt = np.argsort(values, kind="stable")
        jobs = []
        for d in {"up": [1], True: [1], "down": [-1], "both": [1, -1]}[warm_start]:
            order = srt if d > 0 else srt[::-1]
            jobs.append((d, order, ex.submit(run, order, True)))
        done = [(d, order, fut.result()) for d, order, fut in jobs]
    else:
        # handed out on demand, in shrinking blocks, as the plain diagram's runs
        run_blocks(n, lambda idx: done.append((0, idx, run(idx, False))), order=interleaved(n),
                   max_block=max(1, BLOCK_OUTPUT // max(1, cap_per_value)), workers=workers)
    parts = []
    lam_all = np.full(n, -math.inf)
    for d, order, (out_t, out_v, counts, st, lam) in done:
        parts.append((order, st, counts, _rows(values, order, T_of, out_t, out_v, counts, d)))
        # warm "both": the larger of the two directions' exponents (NaN if either is)
        lam_all[order] = np.maximum(lam_all[order], lam)
    bif = merge_parts(name, values, parts, time.perf_counter() - tic)
    return dataclasses.replace(bif, lyapunov=lam_all, params=p, options=sweep_options(
        t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0, warm_start=warm_start,
        lyapunov=True))


# ------------------------------------------------------------------ chunked sweeps

#: values per bifurcation chunk; rows per regime-map block (progress and cancel)
VALUES_PER_CHUNK = 64
ROWS_PER_BLOCK = 2


def merge_bifurcations(parts: list) -> Bifurcation:
    """One Bifurcation of successive chunks of values (as :func:`iter_bifurcation` yields)."""
    first = parts[0]
    offsets = np.cumsum([0] + [b.values.size for b in parts[:-1]])
    cat = np.concatenate
    lyap = None if first.lyapunov is None else cat([b.lyapunov for b in parts])
    return dataclasses.replace(
        first, values=cat([b.values for b in parts]), param=cat([b.param for b in parts]),
        v=cat([b.v for b in parts]), t=cat([b.t for b in parts]),
        phase=cat([b.phase for b in parts]),
        index=cat([b.index + o for b, o in zip(parts, offsets)]),
        direction=cat([b.direction for b in parts]), status=cat([b.status for b in parts]),
        n_impacts=cat([b.n_impacts for b in parts]),
        elapsed=float(sum(b.elapsed for b in parts)), lyapunov=lyap)


def _bifurcation_in_chunks(p, name, values, *args, progress=None, cancel=None, chunk: int = VALUES_PER_CHUNK,
                **kwargs) -> Bifurcation:
    """:func:`impactlib.bifurcation` in chunks of ``chunk`` values, with ``progress`` and
    ``cancel`` (see :mod:`impactlib.progress`).  A warm-started sweep is one chain: it reports once, at
    its end, and cannot be stopped midway."""
    values = _values_array(name, values)
    update, close = reporter(progress, values.size, "values")
    try:
        if kwargs.get("warm_start"):
            bif = bifurcation(p, name, values, *args, **kwargs)
            update(values.size)
            return bif
        parts = []
        for a in range(0, values.size, chunk):
            if parts and stopped(cancel):
                break
            parts.append(bifurcation(p, name, values[a:a + chunk], *args, **kwargs))
            update(min(values.size, a + chunk))
        return merge_bifurcations(parts)
    finally:
        close()


def iter_regime_map(p, name_x, values_x, name_y, values_y, *args, rows=ROWS_PER_BLOCK, **kwargs):
    """Yield the RegimeMap of successive blocks of rows (values of ``name_y``, all of
    ``values_x`` each); :func:`merge_regime_maps` joins them.  Stop iterating to cancel.

    ``rows`` is the rows per block, or a callable ``rows(done, elapsed)`` giving the next
    block's rows from the rows done so far and the seconds they took (a small first
    block for a quick picture, later ones sized from the measured rate).  Other
    arguments as :func:`regime_map`."""
    if not callable(rows) and (isinstance(rows, bool) or not isinstance(rows, (int, np.integer))
                               or rows < 1):
        raise ValueError(f"rows={rows!r} must be a whole number >= 1 or a callable "
                         "rows(done, elapsed)")
    vy = _values_array(name_y, values_y)
    tic = time.perf_counter()
    a = 0
    while a < vy.size:
        size = max(1, int(rows(a, time.perf_counter() - tic) if callable(rows) else rows))
        yield regime_map(p, name_x, values_x, name_y, vy[a:a + size], *args, **kwargs)
        a += size


def merge_regime_maps(parts: list) -> RegimeMap:
    """One RegimeMap of successive row blocks (as :func:`iter_regime_map` yields)."""
    first = parts[0]
    motions, row = {}, 0
    for rm in parts:
        motions.update({(iy + row, ix): mo for (iy, ix), mo in rm.motions.items()})
        row += rm.values_y.size
    return dataclasses.replace(
        first, values_y=np.concatenate([rm.values_y for rm in parts]),
        impacts=np.concatenate([rm.impacts for rm in parts]),
        period=np.concatenate([rm.period for rm in parts]),
        status=np.concatenate([rm.status for rm in parts]),
        elapsed=float(sum(rm.elapsed for rm in parts)), motions=motions)


def _regime_map_in_blocks(p, name_x, values_x, name_y, values_y, *args, progress=None, cancel=None,
               rows: int = ROWS_PER_BLOCK, **kwargs) -> RegimeMap:
    """:func:`impactlib.regime_map` in blocks of ``rows`` rows, with ``progress`` (rows
    done) and ``cancel`` (see :mod:`impactlib.progress`)."""
    vy = _values_array(name_y, values_y)
    update, close = reporter(progress, vy.size, "rows")
    parts = []
    try:
        for rm in iter_regime_map(p, name_x, values_x, name_y, vy, *args, rows=rows, **kwargs):
            parts.append(rm)
            update(sum(r.values_y.size for r in parts))
            if stopped(cancel):
                break
        return merge_regime_maps(parts)
    finally:
        close()
