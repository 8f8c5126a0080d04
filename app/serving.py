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
