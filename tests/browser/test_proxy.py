"""scripts/nginx.conf in front of two app processes (Debian's nginx on loopback ports).

What a deployment beyond one process needs, checked through the real proxy: requests
without the route cookie spread over both backends, a browser keeps to one backend for
its page, static files and its WebSocket (sticky by cookie), the WebSocket upgrade goes
through, a foreign Origin is refused by the app and a foreign Host by the proxy, and a
Chromium page and a Bokeh client session both get a complete page through it.
"""
from __future__ import annotations

import socket
import sys
import time
import urllib.request
from collections import Counter
from pathlib import Path

import pytest

from test_app_browser import JS, READY, STATE, handle, wait_reconnected, watch_reconnect

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "reliability"))
from rel_proxy import NGINX_CONF, ProxiedApp, Proxy, nginx_binary  # noqa: E402
from rel_server import free_port, open_session, pump, source, websocket_status  # noqa: E402

VIEWS = ("displacement", "phase", "impact_map", "poincare", "bifurcation")

pytestmark = pytest.mark.skipif(nginx_binary() is None,
                                reason="nginx is not installed (scripts/setup.sh --browser)")


@pytest.fixture(scope="module")
def proxied():
    app = ProxiedApp("proxied", extra_args=["--liveness"])
    yield app
    app.stop()


def get(url: str, cookie: str | None = None) -> tuple[int, str | None]:
    req = urllib.request.Request(url, headers={"Cookie": cookie} if cookie else {})
    with urllib.request.urlopen(req, timeout=30) as r:
        r.read()
        return r.status, r.headers.get("Set-Cookie")


def backends_of(proxy, since: int, path: str) -> list[str]:
    return [e["backend"] for e in proxy.access_log()[since:] if f" {path} " in e["request"]]


def check_routes_spread_and_stick(port: int, proxy) -> None:
    base = f"http://localhost:{port}"
    start = len(proxy.access_log())
    cookies = [get(f"{base}/liveness")[1] for _ in range(24)]
    spread = Counter(backends_of(proxy, start, "/liveness"))
    # 24 random routes all on one of two backends: probability 2 ** -23
    assert len(spread) == 2, spread
    assert all(c and c.startswith("impact_route=") and "HttpOnly" in c for c in cookies)

    cookie = cookies[0].split(";")[0]
    start = len(proxy.access_log())
    for _ in range(12):
        status, again = get(f"{base}/liveness", cookie)
        assert status == 200 and again.split(";")[0] == cookie   # the route is kept
    assert len(set(backends_of(proxy, start, "/liveness"))) == 1


def check_websocket_origin(port: int, proxy) -> None:
    # the upgrade passes nginx and the app admits the proxy's own origin, no other
    assert websocket_status(port, f"http://localhost:{port}", session=True) == 101
    for origin in ("http://evil.example", f"http://evil.example:{port}"):
        assert websocket_status(port, origin, session=True) == 403


def check_foreign_host_dropped(port: int, proxy) -> None:
    """DNS rebinding: a page on evil.example whose name now points here sends
    Host = Origin = evil.example, which Tornado's own origin check admits."""
    assert websocket_status(port, "http://evil.example", host="evil.example",
                            session=True) is None
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(b"GET /app HTTP/1.1\r\nHost: evil.example\r\n\r\n")
        assert s.recv(4096) == b""         # nginx closed it without an answer (444)


CHECKS = [check_routes_spread_and_stick, check_websocket_origin, check_foreign_host_dropped]


@pytest.mark.parametrize("check", CHECKS, ids=[c.__name__ for c in CHECKS])
def test_the_proxy(proxied, check):
    check(proxied.port, proxied.proxy)


# (what is broken, how, the check that must then fail)
BREAKAGES = [
    ("round robin", lambda t: t.replace("hash $impact_route consistent;", ""),
     check_routes_spread_and_stick),
    ("ip_hash (one NAT address: one backend)",
     lambda t: t.replace("hash $impact_route consistent;", "ip_hash;"),
     check_routes_spread_and_stick),
    ("no upgrade header", lambda t: t.replace("proxy_set_header Upgrade $http_upgrade;", ""),
     check_websocket_origin),
    ("no Host check", lambda t: t.replace("server_name _;\n        return 444;", "server_name _;\n        location / { proxy_pass http://impact_explorer; proxy_http_version 1.1; proxy_set_header Upgrade $http_upgrade; proxy_set_header Connection $connection_upgrade; proxy_set_header Host $http_host; }"),
     check_foreign_host_dropped),
]


@pytest.mark.parametrize("broken, mutate, check", BREAKAGES, ids=[b[0] for b in BREAKAGES])
def test_each_proxy_check_fails_on_a_broken_config(proxied, broken, mutate, check):
    text = NGINX_CONF.read_text()
    assert mutate(text) != text, f"the mutation for {broken!r} no longer applies"
    port = free_port()
    proxy = Proxy(port, [b.port for b in proxied.backends], text=mutate(text))
    try:
        with pytest.raises(AssertionError):
            check(port, proxy)
    finally:
        proxy.stop()


def test_a_client_session_through_the_proxy_gets_a_complete_page(proxied):
    session = open_session(proxied.url)
    try:
        doc = session.document

        def complete():
            cols = [source(doc, v).data for v in VIEWS]
            return all(len(next(iter(d.values()), [])) > 0 for d in cols) and \
                "complete" in doc.get_model_by_name("bifurcation_figure").title.text
        assert pump(session, complete, 120), [len(next(iter(source(doc, v).data.values())))
                                              for v in VIEWS]
    finally:
        session.close()
    assert proxied.bad_log_lines() == []


def test_a_browser_page_keeps_to_one_backend(page, proxied):
    start = len(proxied.proxy.access_log())
    page.goto(proxied.url)
    try:
        page.wait_for_function(READY, timeout=60_000, polling=100)
    except Exception:
        raise AssertionError(f"page not ready: {page.evaluate(STATE)}") from None
    page.goto("about:blank")               # nginx logs a WebSocket when it closes
    deadline = time.monotonic() + 20
    while True:
        log = proxied.proxy.access_log()[start:]
        if any(e["request"].startswith("GET /app/ws") for e in log) \
                or time.monotonic() > deadline:
            break
        time.sleep(0.2)
    page_hits = [e for e in log if e["request"].startswith("GET /app ")]
    sockets = [e for e in log if e["request"].startswith("GET /app/ws")]
    assert len(page_hits) == 1 and len(sockets) == 1, log
    assert sockets[0]["status"] == "101"
    route = page_hits[0]["route"]
    mine = [e for e in log if e["route"] == route]
    assert {e["backend"] for e in mine} == {page_hits[0]["backend"]}, mine
    assert sockets[0] in mine              # the WebSocket reached the page's backend
    assert proxied.bad_log_lines() == []


def test_a_page_reconnects_through_a_restarted_proxy_to_its_own_session(page, proxied):
    """nginx restarted (every connection through it dropped): the page's reconnect
    carries its route cookie back to the backend that holds its session. Landing on the
    other backend would give it a fresh session there, with r back at its default."""
    page.goto(proxied.url)
    page.wait_for_function(READY, timeout=60_000, polling=100)
    page.evaluate(JS)
    r = handle(page, "r")
    r.focus()
    for _ in range(3):
        r.press("ArrowLeft")
    page.wait_for_function("() => ie.title('bifurcation_figure').includes('r = 0.77,') && "
                           "ie.title('bifurcation_figure').includes('complete')",
                           timeout=30_000)
    page.evaluate("() => { window.__ieNoReload = true; }")
    disp = page.evaluate("ie.data('displacement').x.length + ':' + ie.sum('displacement', 'x')")

    watch_reconnect(page)
    proxied.proxy.stop()                    # every connection through nginx drops
    time.sleep(3.0)
    proxied.proxy = Proxy(proxied.port, [b.port for b in proxied.backends])
    wait_reconnected(page, lambda: page.evaluate(STATE))
    omega = handle(page, "omega")
    omega.focus()
    for _ in range(5):
        omega.press("ArrowRight")
    page.wait_for_function(
        "() => Math.abs(ie.model('bifurcation_marker').location - 2.05) < 1e-9 && "
        f"ie.data('displacement').x.length + ':' + ie.sum('displacement', 'x') !== {disp!r}",
        timeout=60_000)
    assert page.evaluate("() => window.__ieNoReload === true"), "the page was reloaded"
    assert "r = 0.77," in page.evaluate("ie.title('bifurcation_figure')")
    assert proxied.bad_log_lines() == []
