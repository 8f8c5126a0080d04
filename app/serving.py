"""Server-process details that are not part of any session."""
from __future__ import annotations

import asyncio
import logging

from tornado.iostream import StreamClosedError
from tornado.websocket import WebSocketClosedError

log = logging.getLogger(__name__)

_CLOSED = (WebSocketClosedError, StreamClosedError)


def quiet_closed_sockets() -> None:
    """Log a browser that went away mid-message as one line, not as a traceback.

    Panel writes some messages from its own asyncio tasks; when a tab closes while such
    a write is under way, the task fails with WebSocketClosedError and asyncio logs
    "Task exception was never retrieved" with a traceback. Nothing is wrong (the
    session is being torn down), so those are logged as one line; every other
    exception goes to the loop's previous handler unchanged.
    """
    try:
        loop = asyncio.get_running_loop()
    except RuntimeError:
        return
    previous = loop.get_exception_handler()
    if getattr(previous, "_impact_explorer", False):
        return

    def handler(loop, context):
        if isinstance(context.get("exception"), _CLOSED):
            log.info("a browser closed its connection while a message was being sent")
            return
        if previous is not None:
            previous(loop, context)
        else:
            loop.default_exception_handler(context)

    handler._impact_explorer = True
    loop.set_exception_handler(handler)


class _RejectedValueFilter(logging.Filter):
    """Turn a rejected client value into one WARNING line without a traceback.

    A hand-made websocket client can send values no browser sends (a method not in the
    list, a string into a numeric input). Bokeh and Panel refuse them with a ValueError
    and log it at ERROR level with a traceback; nothing is evaluated and the session
    goes on, so one line is the honest record. Other exceptions are left untouched.
    """

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        if not isinstance(exc, (ValueError, TypeError)):
            return True
        record.msg = "rejected a value sent by a client: %s: %s"
        record.args = (type(exc).__name__, str(exc)[:300])
        record.exc_info = None
        record.exc_text = None
        record.levelno, record.levelname = logging.WARNING, "WARNING"
        return True


def _one_line_exception(exc: BaseException) -> None:
    """Panel's exception handler: one line instead of re-raising into the event loop
    (which makes tornado log 'Exception in callback' with a traceback)."""
    log.warning("a callback failed: %s: %s", type(exc).__name__, str(exc)[:300])


def quiet_rejected_values() -> None:
    """Install the filter and Panel's exception handler (idempotent, per process)."""
    import panel as pn

    for name in ("panel.reactive", "bokeh.server.protocol_handler"):
        logger = logging.getLogger(name)
        if not any(isinstance(f, _RejectedValueFilter) for f in logger.filters):
            logger.addFilter(_RejectedValueFilter())
    pn.config.exception_handler = _one_line_exception


def deliver_stranded_writes() -> None:
    """Work around a race in Panel 1.9.4 that leaves a scene update unsent under load.

    Panel writes held model changes itself (``panel.io.document``): when the websocket
    is busy it queues the message in ``_WRITE_MSGS[doc]``, sets ``_WRITE_BLOCK[doc]``
    and retries in a ``_dispatch_msgs`` task. A task that finishes writing deletes the
    block without looking at the queue; a retry task that then finds no block returns,
    so a message queued meanwhile stays there until the session's next change. The user
    moved a slider and nothing happens. Seen under load (24 sessions): 2 of 52 slider
    moves in Chromium and 10 of ~1000 in client sessions never updated; with this
    wrapper none (tests/reliability/test_load.py). The wrapper sends whatever is left.
    Idempotent, per process.
    """
    from panel.io import document as pdoc

    if getattr(pdoc._dispatch_msgs, "_impact_explorer", False):
        return
    original = pdoc._dispatch_msgs

    async def dispatch_msgs(doc):
        if doc not in pdoc._WRITE_BLOCK and pdoc._WRITE_MSGS.get(doc):
            pdoc._WRITE_BLOCK[doc] = True          # a stranded message: send it now
        await original(doc)                         # its retries call this wrapper
        if doc not in pdoc._WRITE_BLOCK and pdoc._WRITE_MSGS.get(doc):
            pdoc._WRITE_BLOCK[doc] = True
            pdoc._dispatch_write_task(doc, dispatch_msgs, doc)

    dispatch_msgs._impact_explorer = True
    pdoc._dispatch_msgs = dispatch_msgs
