"""Classroom Wi-Fi: the page's websocket is cut and restored; the page recovers by itself.

Chromium loads the app through a loopback TCP relay (tcp_relay.Relay). After a setting
is changed in the page, the relay drops every connection in the middle of a server
message (the worst moment: the browser holds part of it) and refuses new ones for a few
seconds, then lets them through again. Panel's reconnect (``pn.extension(reconnect=True)``
in app/app.py) must bring the same page back to the same server session: no reload (a
marker on ``window`` and the Bokeh document object survive), the changed setting is
still in force on the server (its diagram title and the URL), and a slider moved after
the outage updates the views.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from tcp_relay import Relay
from test_app_browser import JS, READY, STATE, handle, wait_reconnected, watch_reconnect

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture()
def relayed(tmp_path):
    """The app served on a free port, reachable through a relay the test can cut."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    relay = Relay(("127.0.0.1", port))
    log = tmp_path / "server.log"
    cmd = [str(Path(sys.executable).with_name("panel")), "serve", "app/app.py",
           "--address", "127.0.0.1", "--port", str(port), "--liveness",
           # the page's origin is the relay's address
           "--allow-websocket-origin", f"127.0.0.1:{relay.port}"]
    with open(log, "wb") as out:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT,
                                start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/liveness", timeout=5):
                    break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    pytest.fail(f"server did not start:\n{log.read_text()[-3000:]}")
                time.sleep(0.3)
        relay.url = f"http://127.0.0.1:{relay.port}/app"
        relay.log = log
        yield relay
    finally:
        relay.close()
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)


def test_page_recovers_after_the_websocket_is_cut_and_keeps_its_settings(page, relayed):
    page.goto(relayed.url)
    try:
        page.wait_for_function(READY, timeout=60_000, polling=100)
    except Exception:
        raise AssertionError(f"page not ready: {page.evaluate(STATE)}") from None
    page.evaluate(JS)

    # a setting changed in the page (r 0.80 -> 0.77): the server session holds it
    r = handle(page, "r")
    r.focus()
    for _ in range(3):
        r.press("ArrowLeft")
    page.wait_for_function("() => ie.title('bifurcation_figure').includes('r = 0.77,') && "
                           "ie.title('bifurcation_figure').includes('complete')",
                           timeout=30_000)
    page.evaluate("() => { window.__ieNoReload = true; window.__ieDoc = Bokeh.documents[0]; }")
    disp = page.evaluate("ie.data('displacement').x.length + ':' + ie.sum('displacement', 'x')")
    watch_reconnect(page)
    console = []
    page.on("console", lambda m: console.append(f"{m.type}: {m.text}"))

    # Wi-Fi gone in the middle of the server's answer to a slider move (omega 2.00 ->
    # 2.01): the browser has part of a message; open sockets dropped, new ones refused
    def diagnose() -> str:
        state = page.evaluate(STATE)
        marker = page.evaluate("ie.model('bifurcation_marker').location")
        return (f"{state}; marker at {marker}; page query {page.evaluate('location.search')}\n"
                f"console:\n" + "\n".join(console[-30:]) +
                f"\nserver log:\n{relayed.log.read_text()[-3000:]}")

    # the page and server settle first (URL, status lines), so that the message cut is the
    # server's answer to the key press below and the key's own message has arrived
    page.wait_for_function("() => location.search.includes('r=0.77')", timeout=10_000)
    relayed.wait_quiet(1.5)
    relayed.cut_mid_message()
    omega = handle(page, "omega")
    omega.focus()
    omega.press("ArrowRight")
    deadline = time.monotonic() + 30
    while relayed.cut_after is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert relayed.cut_after is not None, "the server sent no message to cut"
    time.sleep(4.0)
    assert relayed.refused >= 1, "the page did not try to reconnect while the link was down"
    assert page.evaluate("window.__ieReconnected") == 0
    relayed.restore()
    wait_reconnected(page, lambda: f"cut after {relayed.cut_after!r}; {diagnose()}")

    # more moves after the outage reach the server and come back as new views
    for _ in range(4):
        omega.press("ArrowRight")
    try:
        page.wait_for_function(
            "() => Math.abs(ie.model('bifurcation_marker').location - 2.05) < 1e-9 && "
            f"ie.data('displacement').x.length + ':' + ie.sum('displacement', 'x') !== {disp!r}",
            timeout=30_000)
    except Exception:
        raise AssertionError(f"no update after the reconnect: {diagnose()}") from None
    assert page.evaluate("() => window.__ieNoReload === true && "
                         "Bokeh.documents[0] === window.__ieDoc"), "the page was reloaded"
    # the session is the same one: the r set before the outage still holds there
    assert "r = 0.77," in page.evaluate("ie.title('bifurcation_figure')")
    page.wait_for_function("() => location.search.includes('omega=2.05') && "
                           "location.search.includes('r=0.77')", timeout=10_000)
