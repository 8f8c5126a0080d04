"""The light load client (rel_light_client.py) sees a served page as Bokeh's own client
does, and a refused or closed session is an error at once, never a wait.

The comparison runs both clients on the same served page (the session-wide ``served``
app): the same number of models pulled and in the end, the same model names, the same
column lengths in the five views once both say complete, the same diagram status. The
failures run against the served app (a foreign Origin) and against a small tornado
server on loopback that misbehaves on purpose (closes at once, says nothing, closes
after the pull) and records what the websocket upgrade carried (token, cookie, Origin).
"""
from __future__ import annotations

import asyncio
import json
import re
import threading
import time

import pytest
import tornado.httpserver
import tornado.netutil
import tornado.web
import tornado.websocket

from rel_light_client import (LightSession, ServerError, SessionClosed, SessionRefused,
                              open_light_session)
from rel_load import VIEWS, BokehClient, diagram_complete, five_views
from rel_server import slider


def _complete(session) -> bool:
    doc = session.document
    return session.wait(lambda: five_views(doc) and diagram_complete(doc), 60)


def _seen(doc) -> dict:
    models = doc.models
    return {
        "count": len(models),
        # Panel names its layouts by a process-wide counter (Column00428): counted as kinds
        "names": sorted(re.sub(r"\d{5}$", "#", m.name) for m in models if m.name),
        "columns": {v: {c: len(x) for c, x in doc.get_model_by_name(v).data_source.data.items()}
                    for v in VIEWS},
        "status": doc.get_model_by_name("bifurcation_status").text,
    }


def _differ(a: dict, b: dict) -> dict:
    return {v: (a["columns"][v], b["columns"][v]) for v in VIEWS
            if a["columns"][v] != b["columns"][v]}


@pytest.mark.timeout(120)
# (not named ``page``: pytest-playwright would take it for its browser page fixture)
@pytest.mark.parametrize("get_page", [True, False], ids=["page", "websocket-only"])
def test_light_client_sees_what_bokehs_client_sees(served, get_page):
    offset = served.log_offset()
    light = open_light_session(served.url, page=get_page)
    try:
        bokeh = BokehClient(served.url)
        try:
            assert light.models_at_pull == bokeh.models_at_pull
            assert _complete(light) and _complete(bokeh)
            # complete is not settled: the time window x(t) asks for after the scene may
            # still be on its way to one of them; both take in what comes for a while
            deadline = time.monotonic() + 10
            while True:
                seen_light, seen_bokeh = _seen(light.document), _seen(bokeh.document)
                if seen_light == seen_bokeh or time.monotonic() > deadline:
                    break
                light.wait(lambda: False, 0.2)
                bokeh.wait(lambda: False, 0.2)
        finally:
            bokeh.close()
    finally:
        light.close()
    assert seen_light["columns"] == seen_bokeh["columns"], _differ(seen_light, seen_bokeh)
    assert seen_light == seen_bokeh
    # and what they see is what the page says: one dot per point the status counts
    drawn = int(re.search(r"(\d+) distinct points drawn", seen_light["status"]).group(1))
    assert sum(seen_light["columns"]["bifurcation"].values()) == 2 * drawn
    assert set(VIEWS) <= set(seen_light["names"])
    assert all(n > 0 for cols in seen_light["columns"].values() for n in cols.values())
    assert served.bad_log_lines(offset) == []


@pytest.mark.timeout(120)
def test_a_slider_moved_by_the_light_client_moves_the_scene(served):
    """Setting a widget model's value sends it: the server answers with a new scene."""
    offset = served.log_offset()
    with open_light_session(served.url, {"bif_n": "24"}) as light:
        doc = light.document
        assert _complete(light)
        before = doc.get_model_by_name("displacement").data_source.data["x"]
        omega = slider(doc, "omega")
        omega.value = 2.5 if omega.value != 2.5 else 2.0
        assert light.wait(lambda: doc.get_model_by_name("displacement").data_source.data["x"]
                          is not before, 30)
        assert doc.get_model_by_name("bifurcation_marker").location == omega.value
    assert served.bad_log_lines(offset) == []


def test_a_foreign_origin_is_refused_at_once(served):
    offset = served.log_offset()
    tic = time.monotonic()
    with pytest.raises(SessionRefused, match="403"):
        LightSession(served.url, origin="http://evil.example", timeout=20)
    assert time.monotonic() - tic < 10
    # the server logged its refusal, and nothing worse
    end = time.monotonic() + 10
    while "Refusing websocket connection from Origin 'http://evil.example'" \
            not in served.log_since(offset):
        assert time.monotonic() < end, served.log_since(offset)[-2000:]
        time.sleep(0.1)
    assert served.bad_log_lines(offset) == []


# -- a websocket server that misbehaves ---------------------------------------------------

class _Misbehaving(tornado.websocket.WebSocketHandler):
    """``close``: closes as soon as it opens; ``silent``: never answers; ``pull``: ACK,
    a document with no roots for the pull, then closes; ``error``: ACK, then an ERROR
    reply to the pull."""

    def check_origin(self, origin):
        return True

    def select_subprotocol(self, subprotocols):
        return subprotocols[0] if subprotocols else None

    def initialize(self, mode, seen):
        self.mode, self.seen, self.fragments = mode, seen, []

    async def open(self):
        self.seen.append(dict(self.request.headers))
        if self.mode == "close":
            self.close(1011, "going away")
        elif self.mode in ("pull", "error"):
            await self._send({"msgid": "a1", "msgtype": "ACK"}, {})

    async def on_message(self, message):
        self.fragments.append(message)
        if len(self.fragments) == 3:
            header = json.loads(self.fragments[0])
            self.fragments = []
            if header["msgtype"] == "PULL-DOC-REQ" and self.mode == "error":
                await self._send({"msgid": "a2", "msgtype": "ERROR", "reqid": header["msgid"]},
                                 {"text": "no such document", "traceback": None})
            elif header["msgtype"] == "PULL-DOC-REQ":
                await self._send({"msgid": "a2", "msgtype": "PULL-DOC-REPLY",
                                  "reqid": header["msgid"]},
                                 {"doc": {"title": "t", "roots": []}})
                self.close(1001, "server restarting")

    async def _send(self, header, content):
        for part in (header, {}, content):
            await self.write_message(json.dumps(part))


class _Page(tornado.web.RequestHandler):
    """A page that sets a route cookie (as scripts/nginx.conf does) and holds a token."""

    def get(self):
        self.set_header("Set-Cookie", "impact_route=r42; Path=/; HttpOnly")
        self.write('<script>const render_items = [{"token":"tok-from-page","roots":{}}];'
                   '</script>')


@pytest.fixture
def misbehaving():
    """``start(mode)`` -> (the URL of a page whose websocket misbehaves so, the list of
    the websocket requests' headers)."""
    loop = asyncio.new_event_loop()
    servers = []

    def start(mode: str):
        sockets = tornado.netutil.bind_sockets(0, "127.0.0.1")
        seen: list[dict] = []
        app = tornado.web.Application([(r"/app", _Page),
                                       (r"/app/ws", _Misbehaving, {"mode": mode, "seen": seen})])

        async def serve():
            server = tornado.httpserver.HTTPServer(app)
            server.add_sockets(sockets)
            return server

        servers.append(asyncio.run_coroutine_threadsafe(serve(), loop).result(10))
        return f"http://localhost:{sockets[0].getsockname()[1]}/app", seen

    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    yield start

    async def stop():
        for server in servers:
            server.stop()
            await server.close_all_connections()

    asyncio.run_coroutine_threadsafe(stop(), loop).result(10)
    loop.call_soon_threadsafe(loop.stop)
    thread.join(10)
    loop.close()


def test_a_session_closed_on_opening_is_an_error(misbehaving):
    url, _ = misbehaving("close")
    tic = time.monotonic()
    with pytest.raises(SessionClosed, match="1011"):
        LightSession(url, page=False, timeout=20)
    assert time.monotonic() - tic < 5


def test_a_server_that_never_answers_times_out(misbehaving):
    url, _ = misbehaving("silent")
    tic = time.monotonic()
    with pytest.raises(TimeoutError, match="no ACK"):
        LightSession(url, page=False, timeout=1.5)
    assert 1.4 < time.monotonic() - tic < 5


def test_a_session_closed_while_waiting_is_an_error(misbehaving):
    url, _ = misbehaving("pull")
    session = LightSession(url, page=False, timeout=20)
    try:
        tic = time.monotonic()
        with pytest.raises(SessionClosed, match="1001"):
            session.wait(lambda: False, 30)
        assert time.monotonic() - tic < 5
    finally:
        session.close()


def test_an_error_reply_is_an_error(misbehaving):
    url, _ = misbehaving("error")
    with pytest.raises(ServerError, match="no such document"):
        LightSession(url, page=False, timeout=20)


def test_the_page_token_and_cookies_go_with_the_websocket(misbehaving):
    """As a browser: the session token read from the page is the subprotocol, and the
    page's cookies (a proxy's route) go with the upgrade, so it reaches the same backend."""
    url, seen = misbehaving("close")
    with pytest.raises(SessionClosed):
        LightSession(url, timeout=20)
    [headers] = seen
    assert headers["Sec-Websocket-Protocol"] == "bokeh, tok-from-page"
    assert headers["Cookie"] == "impact_route=r42"
    assert headers["Origin"] == url.rsplit("/", 1)[0]


@pytest.mark.timeout(120)
def test_a_page_gets_its_cached_scene_and_diagram_in_its_first_pull(served):
    """Results the shared caches hold are in the document the page pulls, not sent as
    patches after its "document ready": a second page of the same settings has its five
    views' data and its complete diagram in the pull itself."""
    offset = served.log_offset()
    with open_light_session(served.url) as first:           # fills the caches
        assert _complete(first)
    with open_light_session(served.url, browser=False) as second:
        doc = second.document                  # as pulled (no document_ready sent yet)
        assert five_views(doc), _seen(doc)["columns"]
        assert diagram_complete(doc), doc.get_model_by_name("bifurcation_status").text
    assert served.bad_log_lines(offset) == []
