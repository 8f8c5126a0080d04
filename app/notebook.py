"""The app inside Jupyter: ``explorer()`` makes a session whose work runs in the
background and whose results reach the page through the kernel's own event loop.

In a notebook (``impact_explorer`` when installed, ``app`` in a checkout)::

    from impact_explorer.notebook import explorer, settled
    ex = explorer({"scene": "fig4"})
    ex                      # the whole page as the cell's output
    ex.settings.omega = 2.5
    await settled(ex)       # every job ended, every result applied

Scenes, diagrams, maps and basins are computed on the same threads as in a served app;
what they produce is handed to the kernel's loop (``app.jobs.KernelLoop``) and applied
there, between and during cells, never from a worker thread: the kernel's comms, the
Bokeh models and the widgets are touched by one thread only.
"""
from __future__ import annotations

import asyncio
import time

from .explorer import Explorer
from .jobs import KernelLoop


def explorer(args: dict | None = None, **params) -> Explorer:
    """A new session for a notebook; ``args`` as the URL's query (``{"omega": 2.5}``,
    ``{"scene": "fig4"}``). Call it in a running kernel (a cell, not a thread)."""
    try:
        loop = asyncio.get_running_loop()
    except RuntimeError:
        raise RuntimeError("explorer() needs the notebook's running event loop: call it in "
                           "a Jupyter cell (outside one, use Explorer() directly: it runs "
                           "every job at once in the calling thread)") from None
    return Explorer(args, loop=KernelLoop(loop), **params)


def jobs(ex: Explorer) -> list:
    """Every background job of a session (those of modes not opened yet included)."""
    return [ex.scene_job, ex.window_job, ex.accuracy_job, ex.stability_job,
            ex.diagram.job, ex.diagram.branch_job, ex.diagram.class_job,
            ex.research.job, ex.research.boundary_job, *ex.compare.jobs]


def busy(ex: Explorer) -> bool:
    """Some job runs, or a result waits to be applied."""
    return not getattr(ex._loop, "idle", True) or any(not job.done.is_set() for job in jobs(ex))


async def settled(ex: Explorer, timeout: float = 300.0, poll: float = 0.05) -> None:
    """Wait (``await settled(ex)`` in a cell) until no job runs and every result was
    applied; the kernel's loop keeps applying results meanwhile. TimeoutError after
    ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    quiet = 0
    while quiet < 2:       # twice in a row: a result applied may start another job
        await asyncio.sleep(poll)
        quiet = 0 if busy(ex) else quiet + 1
        if time.monotonic() > deadline:
            raise TimeoutError(f"the session was still busy after {timeout:g} s")
