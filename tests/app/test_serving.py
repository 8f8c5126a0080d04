"""Server log hygiene: rejected client values are one WARNING line, not a traceback."""
import logging
import sys

from app.serving import _RejectedValueFilter


def record_for(exc):
    try:
        raise exc
    except Exception:
        info = sys.exc_info()
    return logging.LogRecord("bokeh.server.protocol_handler", logging.ERROR, __file__, 1,
                             "error handling message %r", ("msg",), info)


def test_rejected_value_becomes_one_warning_line():
    rec = record_for(ValueError("failed to validate Spinner.value"))
    assert _RejectedValueFilter().filter(rec)
    assert rec.levelname == "WARNING" and rec.exc_info is None
    text = logging.Formatter("%(levelname)s %(message)s").format(rec)
    assert "Traceback" not in text and "ERROR" not in text and "Spinner" in text


def test_other_errors_keep_their_traceback():
    rec = record_for(RuntimeError("a real bug"))
    assert _RejectedValueFilter().filter(rec)
    assert rec.levelname == "ERROR" and rec.exc_info is not None
