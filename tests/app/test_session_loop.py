"""SessionLoop keeps the order of what the workers send, whatever order Bokeh runs its
next-tick callbacks in (under a hold, Panel 1.9.4 can put a later one first)."""
import asyncio
import logging
from types import SimpleNamespace

from bokeh.document import Document

from app.jobs import SessionLoop


def _loop_with_recorders():
    async def build():
        return SessionLoop(Document())        # on a running loop, as in a served session
    loop = asyncio.run(build())
    wakes, ticks = [], []
    loop._io_loop = SimpleNamespace(add_callback=wakes.append)
    loop.doc.add_next_tick_callback = ticks.append
    return loop, wakes, ticks


def test_functions_run_in_the_order_sent_even_when_bokeh_reorders_its_callbacks():
    loop, wakes, ticks = _loop_with_recorders()
    out = []
    loop(lambda: out.append("before ready"))
    assert out == [] and wakes == []          # nothing before the page is up
    loop.ready()
    assert out == ["before ready"]
    for i in range(5):
        loop(lambda i=i: out.append(i))
    for wake in wakes:                        # the loop thread asks Bokeh for a tick
        wake()
    assert len(ticks) == 5
    for tick in reversed(ticks):              # Bokeh runs them last first
        tick()
    assert out == ["before ready", 0, 1, 2, 3, 4]


def test_a_failing_function_does_not_drop_the_others(caplog):
    loop, wakes, ticks = _loop_with_recorders()
    loop.ready()
    out = []
    loop(lambda: out.append(1))
    loop(lambda: 1 / 0)
    loop(lambda: out.append(3))
    for wake in wakes:
        wake()
    with caplog.at_level(logging.WARNING):
        ticks[0]()
    assert out == [1, 3]
    assert "ZeroDivisionError" in caplog.text and "Traceback" not in caplog.text


def test_a_closed_session_runs_nothing_more():
    loop, wakes, ticks = _loop_with_recorders()
    loop.ready()
    out = []
    loop(lambda: out.append(1))
    loop.close()
    for wake in wakes:
        wake()
    for tick in ticks:
        tick()
    assert out == []
