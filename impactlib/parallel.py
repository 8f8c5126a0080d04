"""The one thread pool of the package and the ways work is handed to it.

Kernels release the GIL (``nogil``), so threads run them in parallel.  Every sweep of
independent starts goes through :func:`run_blocks`: ``workers`` threads take blocks of
jobs from a shared counter (guided self-scheduling), so every core works to the end and
several callers (app sessions) share the cores instead of oversubscribing them.  Whole
tasks of their own (a Lyapunov strip's chunks, basin blocks) go through
:func:`executor` or :func:`run_tasks`.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

_POOL_LOCK = threading.Lock()
_POOL: ThreadPoolExecutor | None = None


def worker_count() -> int:
    """Threads of the pool: IMPACTLIB_WORKERS, else the machine's cores."""
    return max(1, int(os.environ.get("IMPACTLIB_WORKERS", os.cpu_count() or 1)))


def pool() -> ThreadPoolExecutor:
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(max_workers=worker_count(), thread_name_prefix="impactlib")
        return _POOL


class Done:
    """A finished job with the interface of a Future."""

    def __init__(self, value):
        self._value = value

    def result(self):
        return self._value

    def cancel(self):
        return False


class Inline:
    """Executor stand-in that runs each task at once, in the caller's thread."""

    def submit(self, fn, *args, **kwargs):
        return Done(fn(*args, **kwargs))


def executor(workers):
    """The pool for tasks that are whole jobs of their own; inline for ``workers=1``."""
    return Inline() if workers == 1 else pool()


def run_tasks(fn, args_list, workers):
    """fn(*args) for each entry, in order, at most 2 x workers submitted ahead; a
    generator of the results (closing it cancels what has not started)."""
    args_list = list(args_list)
    if workers == 1:
        for args in args_list:
            yield fn(*args)
        return
    ex = executor(workers)
    ahead = 2 * (workers or worker_count())
    pending = []
    nxt = 0
    try:
        while nxt < len(args_list) or pending:
            while nxt < len(args_list) and len(pending) < ahead:
                pending.append(ex.submit(fn, *args_list[nxt]))
                nxt += 1
            yield pending.pop(0).result()
    finally:
        for f in pending:
            f.cancel()


#: jobs are taken in strides of this many, so neighbouring (similarly costly) values
#: spread over the blocks
INTERLEAVE = 16


def interleaved(n: int, stride: int = INTERLEAVE) -> np.ndarray:
    """0, s, 2s, ..., 1, 1 + s, ...: an order of n jobs in which every stretch samples
    the whole range."""
    return np.concatenate([np.arange(j, n, stride) for j in range(min(stride, n))])


def run_blocks(n: int, run_block, *, order: np.ndarray, max_block: int, workers=None,
               cancel=None) -> int:
    """Run n jobs as blocks: run_block(idx) for blocks idx of ``order``, on ``workers``
    threads of the pool, each taking the next block from a shared counter.  Blocks shrink
    as the jobs run out (a quarter of the remaining jobs per worker, at most
    ``max_block``), so no thread idles while another holds a costly stretch.  Once
    ``cancel`` (a threading.Event) is set no block is handed out; blocks under way
    finish.  Returns the number of jobs run; with ``workers=1`` they run in the caller's
    thread."""
    workers = worker_count() if workers is None else max(1, int(workers))
    lock = threading.Lock()
    state = {"next": 0}

    def take():
        with lock:
            a = state["next"]
            if a >= n or (cancel is not None and cancel.is_set()):
                return None
            b = min(n, a + max(1, min(max_block, (n - a) // (4 * workers))))
            state["next"] = b
            return order[a:b]

    def drain():
        ran = 0
        while True:
            idx = take()
            if idx is None:
                return ran
            run_block(idx)
            ran += idx.size

    if workers == 1 or n <= 1:
        return drain()
    futs = [pool().submit(drain) for _ in range(min(workers, n))]
    return sum(f.result() for f in futs)
