"""Server-process details that are not part of any session: log hygiene."""
from __future__ import annotations

import asyncio
import logging

from tornado.iostream import StreamClosedError
from tornado.websocket import WebSocketClosedError

from .bokeh_properties import lighter_properties
from .panel_fixes import (deliver_stranded_writes, quiet_writes_to_a_left_page,
                          tolerate_lost_by_keep_alive)

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


def skip_diagnostics() -> None:
    """Bokeh's development checks off in the served process, two settings Bokeh's
    documentation names as speed-ups: ``perform_document_validation`` (every model of a
    new session's document checked for layout and data mistakes: about 8 % of a served
    session's CPU, profiled) and ``perform_error_diagnostics`` (the signature of every
    callback Panel registers inspected, and close matches looked for when an attribute
    is misspelt, which is raised all the same: about 5 % in process). The pages are
    fixed code: tests/app/test_figure_kit.py validates each mode's document."""
    from bokeh.settings import settings

    settings.perform_document_validation.set_value(False)
    settings.perform_error_diagnostics.set_value(False)


def building():
    """A context in which a new session's page is built without Bokeh's property
    validation (``bokeh.core.property.validation.validate``, Bokeh's documented speed-up
    for code that sets only valid values): about 7 % of a session's CPU in process. The
    page is fixed code: tests/app/test_bokeh_properties.py checks that it comes out the same
    with validation on. Process-wide while it lasts, and a build runs on the server's
    event loop start to end, so nothing a user sends is applied inside it."""
    from bokeh.core.property.validation import validate

    return validate(False)


def install() -> None:
    """Everything a served process needs once: quiet logs, the Panel workarounds, and
    Bokeh without its development diagnostics."""
    quiet_closed_sockets()
    quiet_rejected_values()
    deliver_stranded_writes()
    tolerate_lost_by_keep_alive()
    quiet_writes_to_a_left_page()
    lighter_properties()
    skip_diagnostics()
