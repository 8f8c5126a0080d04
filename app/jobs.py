"""One "latest wins" background job, used for every piece of a session's long work.

A ``Job`` runs ``work(request, ticket)`` off the event loop, one request at a time.
Submitting a request while one runs supersedes it: its ticket stops being ``live``
(results it sends are dropped, its ``on_cancel`` hooks run), and only the newest
request waiting is run next; those in between are skipped. So a slider dragged
through twenty values computes perhaps three scenes, and the last one shown is always
the last one asked for.

The work reports back through its ticket: ``ticket.send(fn, *args)`` runs ``fn`` on
the session's event loop (holding the document, so all its model changes go out in
one message) if the ticket is still live. A job with ``on_result`` sends the value
``work`` returns (or the exception it raised) by itself; a streaming job (the
bifurcation diagram) sends as it goes and calls ``ticket.finish()`` at the end.
``done`` is set while no request is in flight.
"""
from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import Executor

import panel as pn
from panel.io.state import set_curdoc

log = logging.getLogger(__name__)


def session_doc():
    """The served session's Bokeh document, or None outside a server (tests)."""
    doc = pn.state.curdoc
    return doc if doc is not None and doc.session_context is not None else None


class SessionLoop:
    """``loop(fn)`` runs ``fn`` on the session's event loop (safe from any thread),
    holding the document so that all its model changes go out in one message; without
    a server (``doc`` None) it runs ``fn`` at once. Functions run in the order they
    were sent.

    Nothing runs before ``ready()`` (call it from ``pn.state.onload``): Panel 1.9.4
    drops model changes made between the page's document pull and its "document ready"
    (``panel.io.document.hold`` discards them while the session is not connected,
    counting on the full document it serves), so a result applied in that gap would
    never reach the page. Until then, functions wait in order and run at ``ready()``.
    Before the pull there is no gap: ``built()``, called on the loop thread as the
    session's build ends, runs what arrived so far at once, into the page the browser
    pulls (a result from the shared caches goes out with the page, not as a patch
    after it).

    The order is kept here, not left to Bokeh: ``doc.add_next_tick_callback`` called
    from a worker thread while the loop thread holds the document has its
    "callback added" event collected by the hold, and Panel 1.9.4 re-queues collected
    events behind ones that arrived meanwhile, so a diagram's last progress line could
    run after its "complete" one. Workers therefore only wake the loop thread (tornado's
    ``add_callback``, thread-safe and in order); the loop thread asks Bokeh for a
    next-tick callback, which runs every function queued so far, oldest first.
    """

    def __init__(self, doc):
        self.doc = doc
        self._ready = doc is None
        self._queue: list[Callable[[], None]] = []     # sent, not run yet (oldest first)
        self._lock = threading.Lock()
        self._io_loop = None
        if doc is not None:
            from tornado.ioloop import IOLoop
            self._io_loop = IOLoop.current()

    def __call__(self, fn: Callable[[], None]) -> None:
        if self.doc is None:
            fn()
            return
        with self._lock:
            self._queue.append(fn)
            if not self._ready:
                return
        self._io_loop.add_callback(self._wake)

    def built(self) -> None:
        """The session's page is built and not pulled yet (call on the loop thread): what
        waits runs now, and goes out with the page."""
        self._drain()

    def ready(self) -> None:
        """The page is up: run what waited, and from now on run at the next tick."""
        with self._lock:
            self._ready = True
        self._drain()

    def close(self) -> None:
        """The session is gone: forget what waits."""
        with self._lock:
            self._queue.clear()

    def _wake(self) -> None:
        try:
            self.doc.add_next_tick_callback(self._drain)
        except Exception as exc:      # the session was destroyed meanwhile
            log.info("session loop: nothing run: %s", exc)

    def _drain(self) -> None:
        with self._lock:
            fns, self._queue = self._queue, []
        self._run(fns)

    def _run(self, fns) -> None:
        if not fns:
            return
        with set_curdoc(self.doc), pn.io.hold(self.doc):
            run_each(fns)


def run_each(fns) -> None:
    """Call each of ``fns`` in order; one failed update must not drop the others."""
    for fn in fns:
        try:
            fn()
        except Exception as exc:
            log.warning("a session update failed: %s: %s", type(exc).__name__,
                        str(exc)[:300])


class KernelLoop:
    """``loop(fn)`` runs ``fn`` on the thread of an asyncio event loop (a Jupyter
    kernel's own loop), never on the calling worker thread: a session without a server
    whose jobs still run in the background. Functions run in the order they were sent,
    all that waited at once, then Bokeh changes made to displayed figures are pushed to
    the notebook. ``idle`` is True when nothing waits."""

    def __init__(self, loop):
        self.loop = loop
        self._queue: list[Callable[[], None]] = []     # sent, not run yet (oldest first)
        self._lock = threading.Lock()

    def __call__(self, fn: Callable[[], None]) -> None:
        with self._lock:
            self._queue.append(fn)
            if len(self._queue) > 1:       # a wake-up is already on its way
                return
        try:
            self.loop.call_soon_threadsafe(self._drain)
        except RuntimeError as exc:        # the kernel's loop is closed
            log.info("kernel loop: nothing run: %s", exc)
            self.close()

    @property
    def idle(self) -> bool:
        with self._lock:
            return not self._queue

    def close(self) -> None:
        """Forget what waits."""
        with self._lock:
            self._queue.clear()

    def _drain(self) -> None:
        with self._lock:
            fns, self._queue = self._queue, []
        run_each(fns)
        push_displayed()


def push_displayed() -> None:
    """Send what changed in the Bokeh models of every output shown in the notebook.

    Panel holds a notebook output's document and sends its held changes when one of its
    own widgets changes; a view that assigns ``source.data`` changes a Bokeh model only,
    which Panel sends on ``push_notebook`` (pushing a document with no change sends
    nothing)."""
    from panel.io.notebook import push_on_root
    from panel.io.state import state

    for ref in list(state._views):
        try:
            push_on_root(ref)
        except Exception as exc:            # an output closed meanwhile
            log.info("notebook push skipped: %s", exc)


class Ticket:
    """One request of a ``Job``, as its work sees it."""

    def __init__(self, job: "Job", generation: int, request):
        self.job, self.generation, self.request = job, generation, request
        self._hooks: list[Callable[[], None]] = []
        self._finished = False

    @property
    def live(self) -> bool:
        """Still the job's current request (not superseded, not cancelled)."""
        return self.job.generation == self.generation

    def send(self, fn: Callable, *args) -> None:
        """Run ``fn(*args)`` on the session's event loop if this ticket is still live."""
        def guarded():
            if self.live:
                fn(*args)
        try:
            self.job.dispatch(guarded)
        except Exception as exc:       # the session went away
            log.info("%s: result dropped: %s", self.job.name, exc)
            self.job.cancel()

    def on_cancel(self, hook: Callable[[], None]) -> None:
        """Call ``hook`` (from any thread) once this ticket is superseded or cancelled."""
        with self.job.lock:
            if self.live and not self._finished:
                self._hooks.append(hook)
                return
        hook()

    def finish(self) -> None:
        """The work of this ticket is complete (streaming jobs)."""
        with self.job.lock:
            self._finished = True
            self._hooks.clear()
            if self.live:
                self.job.done.set()

    def _cancelled(self) -> None:
        with self.job.lock:
            hooks, self._hooks = self._hooks, []
        for hook in hooks:
            try:
                hook()
            except Exception as exc:           # a hook must not break the caller
                log.warning("%s: cancel hook failed: %s", self.job.name, exc)


class Job:
    """Background work of one session where the latest request wins.

    Parameters
    ----------
    name : str
        For log lines.
    work : callable
        ``work(request, ticket)``; runs in ``pool`` (or in the caller's thread when
        ``pool`` is None: a session without a server, as in tests).
    dispatch : callable
        ``dispatch(fn)`` runs ``fn`` on the session's event loop.
    on_result : callable, optional
        ``on_result(request, result)`` on the event loop with what ``work`` returned
        (or the exception it raised). Without it the job streams (see ``Ticket``).
    show_stale : bool
        Deliver a superseded request's result as well (a scene a little behind the
        slider is better than none while the newest one is computed).
    """

    def __init__(self, name: str, work: Callable, dispatch: Callable, *,
                 pool: Executor | None = None, on_result: Callable | None = None,
                 show_stale: bool = False):
        self.name, self.work, self.dispatch = name, work, dispatch
        self.pool, self.on_result, self.show_stale = pool, on_result, show_stale
        self.lock = threading.Lock()
        self.generation = 0
        self.done = threading.Event()
        self.done.set()
        self.sent = threading.Event()          # a result is on its way to the loop
        self._ticket: Ticket | None = None     # the newest request
        self._waiting: Ticket | None = None    # submitted while the worker was busy
        self._busy = False

    def submit(self, request) -> Ticket:
        """Ask for ``request``; supersedes any earlier request."""
        with self.lock:
            self.generation += 1
            old, ticket = self._ticket, Ticket(self, self.generation, request)
            self._ticket = ticket
            self.done.clear()
            start = not self._busy
            if start:
                self._busy = True
            else:
                self._waiting = ticket
        if old is not None:
            old._cancelled()
        if start:
            if self.pool is None:
                self._run(ticket)
            else:
                self._start(ticket)
        return ticket

    def cancel(self) -> None:
        """Drop the current request (its results are no longer shown)."""
        with self.lock:
            self.generation += 1
            old, self._ticket, self._waiting = self._ticket, None, None
            self.done.set()
        if old is not None:
            old._cancelled()

    def _start(self, ticket: Ticket) -> None:
        try:
            self.pool.submit(self._run, ticket)
        except RuntimeError:                # interpreter shutting down
            with self.lock:
                self._busy = False

    def _run(self, ticket: Ticket) -> None:
        while ticket is not None:
            try:
                result = self.work(ticket.request, ticket)
            except Exception as exc:        # reported through on_result, one log line
                log.warning("%s failed: %s: %s", self.name, type(exc).__name__, exc)
                result = exc
            if self.on_result is not None:
                self._deliver(ticket, result)
            with self.lock:
                ticket, self._waiting = self._waiting, None
                if ticket is None:
                    self._busy = False

    def _deliver(self, ticket: Ticket, result) -> None:
        def deliver():
            if ticket.live or self.show_stale:
                self.on_result(ticket.request, result)
            ticket.finish()
        try:
            self.dispatch(deliver)
            self.sent.set()
        except Exception as exc:            # the session went away
            log.info("%s: result dropped: %s", self.name, exc)
            self.cancel()
