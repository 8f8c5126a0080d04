"""Bifurcation sweeps, regime maps and basins on a Dask cluster (optional extra ``dask``).

The parameter grid is cut into chunks; each chunk is one task that runs the ordinary
local sweep on one thread (``impactlib.bifurcation(..., workers=1)`` for a block of
values, ``impactlib.regime_map(..., workers=1)`` for a block of rows), and the chunks are
put back together in order.  Every value is an independent run (or, with warm start, one
sequential continuation per direction), so the result is the local run's, row for row.
Basins run the local driver (:func:`impactlib.iter_basins`) with its blocks of rows sent
to the cluster instead of the thread pool; the attractors are told apart on the caller's
side, block after block in row order, as locally::

    from dask.distributed import Client
    from impactlib import distributed as ild

    with Client("tcp://scheduler:8786") as client:
        bif = ild.bifurcation(client, il.Params(), "omega", np.linspace(0.1, 5, 100_000))
        rmap = ild.regime_map(client, il.Params(), "omega", wx, "r", wy)
        bas = ild.basins(client, il.Params(omega=2.62), (0, 1), (-1, 1), n=(200, 200))

Nothing here imports dask: the caller brings a ``distributed.Client`` (install with
``pip install impact-explorer[dask]``), so ``impactlib`` works without the extra.  Each
worker needs ``impactlib`` installed; Numba compiles (or loads its cache) once per
worker process.
"""
from __future__ import annotations

import collections
import dataclasses
import math
import time

import numpy as np

from ..analysis import basins as _basins
from ..model import Params, RunLimits
from .diagrams import (CAP_PER_VALUE, Bifurcation, RegimeMap, _check_sweep, merge_parts,
                     _values_array, sweep_options, bifurcation as _local_bifurcation,
                     regime_map as _local_regime_map)

TASKS_PER_THREAD = 4     # chunks per worker thread: enough to balance uneven values


def _check_client(client):
    if not (hasattr(client, "map") and hasattr(client, "gather")):
        raise TypeError("client must be a dask.distributed.Client (pip install "
                        f"impact-explorer[dask]), got {type(client).__name__}")


def _thread_count(client) -> int:
    try:
        return max(1, sum(client.nthreads().values()))
    except Exception:   # a client without live workers yet: fall back to one
        return 1


def _edges(n: int, size: int):
    return [(a, min(a + size, n)) for a in range(0, n, size)]


def _default_chunk(client, n: int, minimum: int) -> int:
    return max(minimum, math.ceil(n / (TASKS_PER_THREAD * _thread_count(client))))


# ---------------------------------------------------------------- tasks (run on workers)


def _bifurcation_task(p, name, values, kwargs):
    return _local_bifurcation(p, name, values, workers=1, **kwargs)


def _regime_task(p, name_x, values_x, name_y, values_y, kwargs):
    rm = _local_regime_map(p, name_x, values_x, name_y, values_y, workers=1, **kwargs)
    return rm.impacts, rm.period, rm.status, rm.motions


# ---------------------------------------------------------------- client side


def bifurcation(client, p: Params, name: str, values, t_end: float = 500.0,
                t_record: float = 250.0, method: str = "exact", *, chunk: int | None = None,
                x0: float | None = None, v0: float = 0.0, warm_start: bool | str = False,
                dt: float | None = None, rtol: float = 1e-6, atol: float = 1e-9,
                cap_per_value: int = CAP_PER_VALUE, max_impacts: int = 1_000_000,
                max_steps: int = 20_000_000, lyapunov: bool = False) -> Bifurcation:
    """:func:`impactlib.bifurcation` with the values spread over a Dask cluster.
    ``lyapunov=True`` brings each value's largest exponent along, as the local run.

    Parameters
    ----------
    client : dask.distributed.Client
    chunk : int, optional
        Values per task; default splits the values into about four tasks per worker
        thread (at least 16 values each).  Ignored with ``warm_start``, which is one
        sequential continuation per direction ("both": the two run side by side).
    Other parameters as :func:`impactlib.bifurcation`.

    Returns
    -------
    Bifurcation
        Identical rows, in the same order, to the local run; ``elapsed`` is the wall time
        seen by the caller.
    """
    _check_client(client)
    # validate here, once, so a bad argument fails before anything is sent
    _check_sweep(p, [name], t_end, t_record, x0, v0, method, dt, rtol, atol)
    values = _values_array(name, values)
    if warm_start not in (False, True, "up", "down", "both"):
        raise ValueError(f"warm_start={warm_start!r} must be False, 'up', 'down' or 'both'")
    if chunk is not None and (isinstance(chunk, bool) or int(chunk) != chunk or chunk < 1):
        raise ValueError(f"chunk={chunk!r} must be a whole number >= 1")
    kwargs = dict(t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0, dt=dt,
                  rtol=rtol, atol=atol, cap_per_value=cap_per_value,
                  max_impacts=max_impacts, max_steps=max_steps, lyapunov=lyapunov)
    tic = time.perf_counter()

    def finish(bif, lams):
        # the exponents per value as the local run merges them (the larger of two
        # directions), and the same recorded settings
        lam = None
        if lyapunov:
            lam = np.full(values.size, -math.inf)
            for pos, part in lams:
                lam[pos] = np.maximum(lam[pos], part)
        opts = dict(t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0,
                    warm_start=warm_start)
        opts.update(dict(lyapunov=True) if lyapunov else dict(dt=dt, rtol=rtol, atol=atol))
        return dataclasses.replace(bif, lyapunov=lam, params=p, options=sweep_options(**opts))

    if warm_start:
        directions = ["up", "down"] if warm_start == "both" else [
            "up" if warm_start is True else warm_start]
        futs = client.map(_bifurcation_task, [p] * len(directions), [name] * len(directions),
                          [values] * len(directions),
                          [dict(kwargs, warm_start=d) for d in directions], pure=False)
        whole = np.arange(values.size)
        done = client.gather(futs)
        parts = [(whole, b.status, b.n_impacts, _row_arrays(b, 0)) for b in done]
        return finish(merge_parts(name, values, parts, time.perf_counter() - tic),
                      [(whole, b.lyapunov) for b in done])
    size = int(chunk) if chunk else _default_chunk(client, values.size, 16)
    edges = _edges(values.size, size)
    futs = client.map(_bifurcation_task, [p] * len(edges), [name] * len(edges),
                      [values[a:b] for a, b in edges], [kwargs] * len(edges), pure=False)
    # each task numbered its values from 0: shift to positions in the full array
    done = client.gather(futs)
    parts = [(np.arange(a, b), part.status, part.n_impacts, _row_arrays(part, a))
             for (a, b), part in zip(edges, done)]
    return finish(merge_parts(name, values, parts, time.perf_counter() - tic),
                  [(np.arange(a, b), part.lyapunov) for (a, b), part in zip(edges, done)])


def _row_arrays(b: Bifurcation, offset: int):
    return b.param, b.v, b.t, b.phase, b.index + offset, b.direction


def regime_map(client, p: Params, name_x: str, values_x, name_y: str, values_y,
               t_end: float = 500.0, t_record: float = 250.0, method: str = "exact", *,
               rows_per_task: int | None = None, x0: float | None = None, v0: float = 0.0,
               dt: float | None = None, rtol: float = 1e-6, atol: float = 1e-9,
               max_impacts: int = 1_000_000, max_steps: int = 20_000_000) -> RegimeMap:
    """:func:`impactlib.regime_map` with blocks of rows (values_y) spread over a cluster.

    Parameters
    ----------
    client : dask.distributed.Client
    rows_per_task : int, optional
        Rows of the (ny, nx) grid per task; default about four tasks per worker thread.
    Other parameters as :func:`impactlib.regime_map`.

    Returns
    -------
    RegimeMap
        Identical to the local map; ``elapsed`` is the caller's wall time.
    """
    kwargs = dict(t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0, dt=dt,
                  rtol=rtol, atol=atol, max_impacts=max_impacts, max_steps=max_steps)
    vx, vy = _check_map(client, p, name_x, values_x, name_y, values_y, rows_per_task, kwargs)
    tic = time.perf_counter()
    size = int(rows_per_task) if rows_per_task else _default_chunk(client, vy.size, 1)
    return _map_of_blocks(p, name_x, vx, name_y, vy, kwargs, tic,
                          list(_regime_blocks(client, p, name_x, vx, name_y, vy, kwargs, size)))


def _check_map(client, p, name_x, values_x, name_y, values_y, rows_per_task, kwargs):
    _check_client(client)
    _check_sweep(p, [name_x, name_y], kwargs["t_end"], kwargs["t_record"], kwargs["x0"],
                 kwargs["v0"], kwargs["method"], kwargs["dt"], kwargs["rtol"], kwargs["atol"])
    if name_x == name_y:
        raise ValueError(f"name_x and name_y are both {name_x!r}")
    vx = _values_array(name_x, values_x)
    vy = _values_array(name_y, values_y)
    if rows_per_task is not None and (isinstance(rows_per_task, bool)
                                      or int(rows_per_task) != rows_per_task
                                      or rows_per_task < 1):
        raise ValueError(f"rows_per_task={rows_per_task!r} must be a whole number >= 1")
    return vx, vy


def _regime_blocks(client, p, name_x, vx, name_y, vy, kwargs, size):
    """((a, b), block) for the row blocks [a, b) of the map, in order, all submitted at
    once; closing the generator cancels the blocks not returned yet."""
    edges = _edges(vy.size, size)
    n = len(edges)
    futs = collections.deque(client.map(_regime_task, [p] * n, [name_x] * n, [vx] * n,
                                        [name_y] * n, [vy[a:b] for a, b in edges],
                                        [kwargs] * n, pure=False))
    try:
        for edge in edges:
            yield edge, futs.popleft().result()
    finally:
        if futs:
            client.cancel(list(futs))


def _map_of_blocks(p, name_x, vx, name_y, vy, kwargs, tic, blocks) -> RegimeMap:
    """The RegimeMap of rows vy from their blocks ((a, b), (impacts, period, status,
    motions)) (row a of vy first)."""
    a0 = blocks[0][0][0]
    impacts = np.concatenate([b[0] for _, b in blocks])
    period = np.concatenate([b[1] for _, b in blocks])
    status = np.concatenate([b[2] for _, b in blocks])
    motions = {(iy + a - a0, ix): mo
               for (a, _), b in blocks for (iy, ix), mo in b[3].items()}
    opts = {k: kwargs[k] for k in ("t_end", "t_record", "method", "x0", "v0", "dt", "rtol",
                                   "atol")}
    return RegimeMap(name_x, vx, name_y, vy, impacts, period, status,
                     time.perf_counter() - tic, motions, params=p,
                     options=sweep_options(**opts))


def iter_regime_map(client, p: Params, name_x: str, values_x, name_y: str, values_y,
                    t_end: float = 500.0, t_record: float = 250.0, method: str = "exact", *,
                    rows_per_task: int | None = None, x0: float | None = None,
                    v0: float = 0.0, dt: float | None = None, rtol: float = 1e-6,
                    atol: float = 1e-9, max_impacts: int = 1_000_000,
                    max_steps: int = 20_000_000):
    """:func:`impactlib.iter_regime_map` on a cluster: every block of ``rows_per_task``
    rows is submitted at once and the blocks' RegimeMaps are yielded in row order as they
    finish (``impactlib.sweeps.diagrams.merge_regime_maps`` joins them into the local
    map).  Stop
    iterating (or ``close()``) to cancel the blocks still on the cluster.  Validation
    happens here, before anything is sent.  Other parameters as :func:`regime_map`."""
    kwargs = dict(t_end=t_end, t_record=t_record, method=method, x0=x0, v0=v0, dt=dt,
                  rtol=rtol, atol=atol, max_impacts=max_impacts, max_steps=max_steps)
    vx, vy = _check_map(client, p, name_x, values_x, name_y, values_y, rows_per_task, kwargs)
    size = int(rows_per_task) if rows_per_task else _default_chunk(client, vy.size, 1)

    def stream():
        blocks = _regime_blocks(client, p, name_x, vx, name_y, vy, kwargs, size)
        tic = time.perf_counter()      # a block's elapsed: the wait for it
        try:
            for (a, b), block in blocks:
                yield _map_of_blocks(p, name_x, vx, name_y, vy[a:b], kwargs, tic,
                                     [((a, b), block)])
                tic = time.perf_counter()
        finally:
            blocks.close()
    return stream()



# ---------------------------------------------------------------- basins


class _KnownChaos:
    """What a basins block reads of the caller's attractor registry, sent to a worker:
    the chaotic attractors' boxes known when the block was handed out (a start that
    fills one stops early)."""

    def __init__(self, chaos_boxes):
        self.chaos_boxes = chaos_boxes


def _cluster_tasks(client, ahead: int):
    """A ``tasks(fn, args_list)`` for the basins driver: at most ``ahead`` blocks on the
    cluster at a time, results in order; closing it cancels the blocks not returned."""
    def tasks(fn, args_list):
        pending = collections.deque()
        todo = iter(args_list)
        try:
            while True:
                while len(pending) < ahead:
                    args = next(todo, None)
                    if args is None:
                        break
                    reg, *rest = args
                    pending.append(client.submit(fn, _KnownChaos(reg.chaos_boxes), *rest,
                                                 pure=False))
                if not pending:
                    return
                yield pending.popleft().result()
        finally:
            if pending:
                client.cancel(list(pending))
    return tasks


def iter_basins(client, p: Params, x_range, v_range, n=(100, 100), phase: float = 0.0, *,
                max_periods: int = 1000, n_window: int = 128,
                rows_per_block: int | None = None, time_limit: float | None = None,
                limits: RunLimits = RunLimits()):
    """:func:`impactlib.iter_basins` with the blocks of rows computed on a cluster.

    Yields the same :class:`~impactlib.analysis.basins.BasinRows` as the local stream, in
    row order; stop iterating (or ``close()``) to cancel the blocks still on the cluster.
    At most two blocks per worker thread are on the cluster at a time (as the local run
    keeps its pool busy).  Arguments as :func:`impactlib.basins`; validation happens here,
    before anything is sent.
    """
    _check_client(client)
    xr, vr, (nx, nv), phase = _basins._check(p, x_range, v_range, n, phase, max_periods,
                                             n_window, time_limit)
    return _basins._iter(p, xr, vr, nx, nv, phase, max_periods, n_window, rows_per_block,
                         None, time_limit, limits,
                         tasks=_cluster_tasks(client, 2 * _thread_count(client)))


def basins(client, p: Params, x_range, v_range, n=(100, 100), phase: float = 0.0, *,
           max_periods: int = 1000, n_window: int = 128, time_limit: float | None = None,
           limits: RunLimits = RunLimits()) -> "_basins.Basins":
    """:func:`impactlib.basins` with the grid's blocks of rows computed on a cluster.

    Returns
    -------
    Basins
        Equal (``==``: labels, attractors, work per start, message) to the local result.
        One exception, as between two local runs: where a chaotic attractor is found in
        the middle of the grid, a start in a block already handed out follows its full
        ``max_periods`` instead of stopping on the attractor's box; its label is the same,
        its entry in ``periods`` larger.  ``elapsed`` is the caller's wall time.
    """
    _check_client(client)
    xr, vr, (nx, nv), ph = _basins._check(p, x_range, v_range, n, phase, max_periods,
                                          n_window, time_limit)
    tic = time.perf_counter()
    blocks = iter_basins(client, p, xr, vr, (nx, nv), ph, max_periods=max_periods,
                         n_window=n_window, time_limit=time_limit, limits=limits)
    return _basins.collect(p, xr, vr, nx, nv, ph, tic, blocks)


__all__ = ["bifurcation", "regime_map", "iter_regime_map", "basins", "iter_basins"]
