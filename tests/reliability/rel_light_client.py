"""A light load client for a served Bokeh/Panel page: Bokeh's websocket protocol spoken
directly, the document kept as plain data (rel_light_doc.py), no Bokeh models built.

What one session does, as a browser tab does it (checked against Chromium's frames):
GET the page (the server makes the session and renders the HTML; the session token is
read from it, cookies it sets, such as a proxy's route, go with the websocket;
``page=False`` instead makes a session id and token here, as Bokeh's
Python client does, and the server makes the session when the websocket opens), open
``ws://HOST/APP/ws`` with the token as subprotocol and the page's Origin, wait for the
ACK, send PULL-DOC-REQ and keep the PATCH-DOCs that come before the reply (applied right
after it), then send what the page sends once it is shown: each BrowserInfo property
(dark mode, pixel ratio, language, ...) and the ``document_ready`` event (Panel then
runs the page's onload callbacks). While waiting it applies the server's patches; when
the server moves the page's Location (``search``), it answers with the new ``href``,
as Panel's Location view does. Setting a model attribute sends a ModelChanged.

What it does not do: load the page's JavaScript and CSS, run BokehJS layout and
rendering, and send what only those produce (figure sizes, auto-ranged start/end).
So it measures the server, not a browser. Errors are raised, never waited out: a refused
upgrade (bad Origin: HTTP 403) is ``SessionRefused``, a closed socket ``SessionClosed``,
an ERROR reply ``ServerError``, no ACK or pull reply in time ``TimeoutError``.
"""
from __future__ import annotations

import http.client
import json
import re
import time
import urllib.parse
import uuid

from rel_light_doc import LightDocument
from rel_websocket import SessionClosed, SessionRefused, WebSocket

__all__ = ["LightSession", "open_light_session", "SessionRefused", "SessionClosed",
           "ServerError"]

#: What a headless Chromium's BrowserInfo view sent on loading the page.
BROWSER_INFO = {"dark_mode": False, "device_pixel_ratio": 1, "language": "en-US",
                "webdriver": False, "timezone": "UTC", "timezone_offset": 0, "webgl": True}


class ServerError(RuntimeError):
    """The server answered a request with an ERROR message."""


class LightSession:
    """One page's session on the server at ``url`` (``http://HOST:PORT/APP``); its
    document is ``self.document`` (a LightDocument). Use from one thread."""

    def __init__(self, url: str, args: dict | None = None, page: bool = True,
                 origin: str | None = None, timeout: float = 30.0, browser: bool = True):
        u = urllib.parse.urlsplit(url)
        self.host, self.port = u.hostname, u.port or 80
        self.origin = origin or f"{u.scheme}://{u.netloc}"
        self.base = f"{u.scheme}://{u.netloc}"
        query = urllib.parse.urlencode(args or {})
        ws_path = u.path.rstrip("/") + "/ws"
        self.cookies: dict[str, str] = {}
        if page:
            token = self._page_token(u.path + (f"?{query}" if query else ""), timeout)
        else:
            from bokeh.util.token import generate_jwt_token, generate_session_id

            token = generate_jwt_token(generate_session_id())
            ws_path += f"?{query}" if query else ""
        self.document = doc = LightDocument()
        doc.send = self._send_patch
        doc.hooks.append(self._location_moved)
        headers = {"Origin": self.origin, "Sec-WebSocket-Protocol": f"bokeh, {token}"}
        if self.cookies:                    # e.g. a proxy's route (scripts/nginx.conf)
            headers["Cookie"] = "; ".join(f"{k}={v}" for k, v in self.cookies.items())
        self.ws = WebSocket(self.host, self.port, ws_path, headers, timeout)
        self.fragments: list = []
        try:
            self._open(time.monotonic() + timeout, browser)
        except BaseException:
            self.ws.close(wait=0.2)
            raise

    def _page_token(self, path: str, timeout: float) -> str:
        conn = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        try:
            conn.request("GET", path, headers={"Accept": "text/html"})
            resp = conn.getresponse()
            body = resp.read().decode(errors="replace")
            for cookie in resp.headers.get_all("Set-Cookie") or []:
                name, _, value = cookie.split(";", 1)[0].partition("=")
                self.cookies[name.strip()] = value.strip()
        finally:
            conn.close()
        if resp.status != 200:
            raise SessionRefused(f"GET {path}: HTTP {resp.status} {resp.reason}")
        found = re.search(r'"token":\s*"([^"]+)"', body)
        if not found:
            raise SessionRefused(f"GET {path}: no session token in the page")
        return found.group(1)

    def _open(self, deadline: float, browser: bool) -> None:
        ack = self._message(deadline)
        if ack is None or ack[0]["msgtype"] != "ACK":
            raise TimeoutError("no ACK from the server" if ack is None else f"not an ACK: {ack[0]}")
        reqid = self._send("PULL-DOC-REQ", {})
        early = []                       # patches sent before the reply: applied after it
        while True:
            msg = self._message(deadline)
            if msg is None:
                raise TimeoutError("no PULL-DOC-REPLY from the server")
            header, content, buffers = msg
            if header.get("reqid") == reqid:
                if header["msgtype"] == "ERROR":
                    raise ServerError(f"pulling the document: {content.get('text')}")
                break
            if header["msgtype"] == "PATCH-DOC":
                early.append(msg)
        self.document.load(content["doc"], buffers)
        self.models_at_pull = len(self.document.reachable())
        for _, content, buffers in early:
            self.document.apply(content["events"], buffers)
        if browser:
            for model in self.document.models:
                if model.__view_model__ == "BrowserInfo":
                    for attr, value in BROWSER_INFO.items():
                        setattr(model, attr, value)
            self._send("PATCH-DOC", {"events": [{
                "kind": "MessageSent", "msg_type": "bokeh_event",
                "msg_data": {"type": "event", "name": "document_ready",
                             "values": {"type": "map"}}}]})

    # -- messages -------------------------------------------------------------------------
    def _send(self, msgtype: str, content: dict) -> str:
        msgid = uuid.uuid4().hex.upper()
        self.ws.send(json.dumps({"msgid": msgid, "msgtype": msgtype}))
        self.ws.send("{}")
        self.ws.send(json.dumps(content))
        return msgid

    def _send_patch(self, events: list) -> None:
        self._send("PATCH-DOC", {"events": events})

    def _message(self, deadline: float):
        """The next whole Bokeh message (header, content, buffers by id), or None at the
        deadline (its fragments so far are kept)."""
        frags = self.fragments
        while True:
            if len(frags) >= 3:
                header = json.loads(frags[0]) if isinstance(frags[0], str) else frags[0]
                frags[0] = header
                if len(frags) == 3 + 2 * header.get("num_buffers", 0):
                    self.fragments = []
                    buffers = {json.loads(frags[i])["id"]: frags[i + 1]
                               for i in range(3, len(frags), 2)}
                    return header, json.loads(frags[2]), buffers
            data = self.ws.recv(deadline)
            if data is None:
                return None
            frags.append(data)

    def _handle(self, msg) -> None:
        header, content, buffers = msg
        if header["msgtype"] == "PATCH-DOC":
            self.document.apply(content["events"], buffers)
        elif header["msgtype"] == "ERROR":
            raise ServerError(f"{content.get('text')} (reply to {header.get('reqid')})")

    def _location_moved(self, id_: str, attr: str) -> None:
        """Panel's Location view: a new pathname, search or hash goes into the address
        bar, and the page sends its new href."""
        doc = self.document
        if attr in ("pathname", "search", "hash") and doc.types[id_].endswith("Location"):
            a = doc.attrs[id_]
            href = f"{self.base}{a.get('pathname', '')}{a.get('search', '')}{a.get('hash', '')}"
            if a.get("href") != href:
                doc.set_local(id_, "href", href)

    # -- what the load script uses ----------------------------------------------------------
    def wait(self, predicate, timeout: float) -> bool:
        """Apply the server's messages until ``predicate()`` holds (True) or ``timeout``
        s pass (False)."""
        deadline = time.monotonic() + timeout
        if predicate():
            return True
        while True:
            msg = self._message(deadline)
            if msg is None:
                return predicate()
            self._handle(msg)
            if predicate():
                return True

    def close(self) -> None:
        self.ws.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_light_session(url: str, args: dict | None = None, retries: int = 3,
                       **kw) -> LightSession:
    """A LightSession, retried (1 s apart) when connecting fails for want of an answer;
    a refusal is raised at once."""
    for attempt in range(retries):
        try:
            return LightSession(url, args, **kw)
        except (OSError, TimeoutError, SessionClosed):
            if attempt == retries - 1:
                raise
            time.sleep(1.0)
    raise AssertionError("unreachable")
