"""Long sweeps that report progress and can be stopped: chunked versions of
:func:`impactlib.bifurcation`, :func:`impactlib.regime_map` and :func:`impactlib.basins`,
and :func:`iter_regime_map`.

``progress`` is ``True`` (a tqdm bar, in a terminal or a notebook), or a callable
``progress(done, total)`` called after each chunk with the values, rows or starts done
(monotone, the last call has done == total unless cancelled). ``cancel`` is a
``threading.Event``: once set, no further chunk starts; the result then holds the chunks
finished (fewer values or rows than asked for, and a Basins result says so in
``complete`` and ``message``). The numbers are those of the one-call functions.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from . import sweeps
from .basins import Basins, iter_basins

#: values per bifurcation chunk; rows per regime-map chunk
CHUNK = 64
ROWS = 2


def reporter(progress, total: int, what: str):
    """(update(done), close()) for a progress setting: None/False, True (tqdm) or callable."""
    if progress is None or progress is False:
        return (lambda done: None), (lambda: None)
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, unit=what)

        def update(done):
            bar.update(done - bar.n)
        return update, bar.close
    if not callable(progress):
        raise ValueError(f"progress={progress!r} must be True, False, None or a callable "
                         "progress(done, total)")
    return (lambda done: progress(done, total)), (lambda: None)


def _stopped(cancel) -> bool:
    return cancel is not None and cancel.is_set()


def merge_bifurcations(parts: list) -> sweeps.Bifurcation:
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


def bifurcation(p, name, values, *args, progress=None, cancel=None, chunk: int = CHUNK,
                **kwargs) -> sweeps.Bifurcation:
    """:func:`impactlib.bifurcation` in chunks of ``chunk`` values, with ``progress`` and
    ``cancel`` (see the module).  A warm-started sweep is one chain: it reports once, at
    its end, and cannot be stopped midway."""
    values = sweeps._values_array(name, values)
    update, close = reporter(progress, values.size, "values")
    try:
        if kwargs.get("warm_start"):
            bif = sweeps.bifurcation(p, name, values, *args, **kwargs)
            update(values.size)
            return bif
        parts = []
        for a in range(0, values.size, chunk):
            if parts and _stopped(cancel):
                break
            parts.append(sweeps.bifurcation(p, name, values[a:a + chunk], *args, **kwargs))
            update(min(values.size, a + chunk))
        return merge_bifurcations(parts)
    finally:
        close()


def iter_regime_map(p, name_x, values_x, name_y, values_y, *args, rows: int = ROWS, **kwargs):
    """Yield the RegimeMap of successive blocks of ``rows`` values of ``name_y`` (all of
    ``values_x`` each); :func:`merge_regime_maps` joins them.  Stop iterating to cancel."""
    vy = sweeps._values_array(name_y, values_y)
    for a in range(0, vy.size, rows):
        yield sweeps.regime_map(p, name_x, values_x, name_y, vy[a:a + rows], *args, **kwargs)


def merge_regime_maps(parts: list) -> sweeps.RegimeMap:
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


def regime_map(p, name_x, values_x, name_y, values_y, *args, progress=None, cancel=None,
               rows: int = ROWS, **kwargs) -> sweeps.RegimeMap:
    """:func:`impactlib.regime_map` in blocks of ``rows`` rows, with ``progress`` (rows
    done) and ``cancel`` (see the module)."""
    vy = sweeps._values_array(name_y, values_y)
    update, close = reporter(progress, vy.size, "rows")
    parts = []
    try:
        for rm in iter_regime_map(p, name_x, values_x, name_y, vy, *args, rows=rows, **kwargs):
            parts.append(rm)
            update(sum(r.values_y.size for r in parts))
            if _stopped(cancel):
                break
        return merge_regime_maps(parts)
    finally:
        close()


def basins(p, x_range, v_range, n=(100, 100), phase: float = 0.0, *, progress=None,
           cancel=None, rows_per_block=None, **kwargs) -> Basins:
    """:func:`impactlib.basins` from the blocks of :func:`impactlib.iter_basins`, with
    ``progress`` (rows done) and ``cancel`` (rows not run stay -1, ``complete`` False)."""
    tic = time.perf_counter()
    gen = iter_basins(p, x_range, v_range, n=n, phase=phase,
                              rows_per_block=rows_per_block, **kwargs)
    nx, nv = (n, n) if np.ndim(n) == 0 else (int(n[0]), int(n[1]))
    update, close = reporter(progress, nv, "rows")
    labels = np.full((nv, nx), -1, dtype=np.int64)
    periods = np.zeros((nv, nx), dtype=np.int64)
    last, cancelled = None, False
    try:
        for blk in gen:
            rws = slice(blk.start, blk.start + blk.labels.shape[0])
            labels[rws], periods[rws] = blk.labels, blk.periods
            last = blk
            update(blk.rows_done)
            if _stopped(cancel) and blk.rows_done < nv:
                cancelled = True
                break
    finally:
        gen.close()
        close()
    atts = last.attractors if last else ()
    counts = np.bincount(labels[labels >= 0], minlength=len(atts))[:len(atts)]
    total = labels.size
    done = last.rows_done if last else 0
    message = (f"cancelled after {done} of {nv} rows" if cancelled
               else last.message if last else "complete")
    return Basins(params=p, phase=float(phase), x=np.linspace(*x_range, nx),
                          v=np.linspace(*v_range, nv), labels=labels, attractors=atts,
                          fractions=counts / total, undecided=float(np.sum(labels < 0)) / total,
                          periods=periods, complete=bool(done == nv and not cancelled),
                          message=message, elapsed=time.perf_counter() - tic)
