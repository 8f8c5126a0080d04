"""A served app on a loopback port, its log and memory, and light Bokeh client sessions.

Used by the reliability tests (bad input over the wire, security, load). The server is
started the way a user starts it (``panel serve app/app.py``), bound to 127.0.0.1 only,
in its own process group so that it and anything it forks stop together.
"""
from __future__ import annotations

import base64
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: Server logs and load figures. Not under test-results/: pytest-playwright empties that
#: folder when the browser tests start, which may be while a reliability server runs.
RESULTS = Path(os.environ.get("RELIABILITY_RESULTS",
                              Path(tempfile.gettempdir()) / "impact-reliability"))

#: What must never appear in the server log: a traceback, an ERROR record, or tornado's
#: "Exception in callback" (a callback that raised into the event loop).
BAD_LOG = re.compile(r"Traceback|\bERROR\b|Exception in callback|error handling message")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Served:
    """``panel serve app/app.py`` on 127.0.0.1:<port>; ``stop()`` ends its process group."""

    def __init__(self, log_name: str, extra_args=(), origin: str | None = "localhost",
                 env: dict | None = None, start_timeout: float = 120.0, probe: bool = False):
        RESULTS.mkdir(parents=True, exist_ok=True)
        self.port = free_port()
        env = dict(env or {})
        self.probe_dir = None
        if probe:       # count live session objects on request (rel_probe.py)
            self.probe_dir = Path(tempfile.mkdtemp(prefix="impact-probe-"))
            env["IMPACT_PROBE_DIR"] = str(self.probe_dir)
            extra_args = [*extra_args, "--setup", str(Path(__file__).with_name("rel_probe.py"))]
        self.log_path = RESULTS / log_name
        panel = Path(sys.executable).with_name("panel")
        cmd = [str(panel), "serve", "app/app.py", "--address", "127.0.0.1",
               "--port", str(self.port), *extra_args]
        # origin=None: no --allow-websocket-origin at all (Bokeh's own default);
        # "localhost": what scripts/app.sh passes when IMPACT_ALLOWED_ORIGINS is unset.
        if origin == "localhost":
            cmd += ["--allow-websocket-origin", f"localhost:{self.port}"]
        elif origin is not None:
            cmd += ["--allow-websocket-origin", origin]
        self.cmd = cmd
        with open(self.log_path, "wb") as out:
            self.proc = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT,
                                         start_new_session=True, env={**os.environ, **env})
        self.base = f"http://localhost:{self.port}"
        self.url = f"{self.base}/app"
        deadline = time.monotonic() + start_timeout
        while True:
            try:
                with urllib.request.urlopen(self.url, timeout=10) as r:
                    if r.status == 200:
                        break
            except OSError:
                pass
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"server did not start; log:\n{self.log()[-3000:]}")
            time.sleep(0.3)

    # -- log -------------------------------------------------------------------------
    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def log_offset(self) -> int:
        return self.log_path.stat().st_size

    def log_since(self, offset: int) -> str:
        with open(self.log_path, "rb") as f:
            f.seek(offset)
            return f.read().decode(errors="replace")

    def bad_log_lines(self, offset: int = 0) -> list[str]:
        return [line for line in self.log_since(offset).splitlines() if BAD_LOG.search(line)]

    # -- process -----------------------------------------------------------------------
    def rss_mb(self) -> float:
        """Resident set size of the server process (VmRSS from /proc), in MB."""
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
        raise RuntimeError("no VmRSS")

    def live_objects(self, timeout: float = 60.0) -> dict:
        """Counts of session objects alive in the server after a full collection."""
        import json

        answer = self.probe_dir / "answer.json"
        answer.unlink(missing_ok=True)
        (self.probe_dir / "request").write_text("?")
        end = time.monotonic() + timeout
        while not answer.exists():
            if time.monotonic() > end:
                raise TimeoutError("the server's probe did not answer")
            time.sleep(0.1)
        return json.loads(answer.read_text())

    def get(self, path: str) -> tuple[int, bytes]:
        try:
            with urllib.request.urlopen(self.base + path, timeout=30) as r:
                return r.status, r.read()
        except urllib.error.HTTPError as err:
            return err.code, err.read()

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)


# -- a server's processes, from /proc --------------------------------------------------

_TICK = os.sysconf("SC_CLK_TCK")


def _stat_fields(pid: str) -> list[str] | None:
    try:
        with open(f"/proc/{pid}/stat") as f:
            text = f.read()
    except OSError:
        return None
    return text[text.rindex(")") + 2:].split()       # fields from 3 (state) on


def group_pids(pgids) -> list[int]:
    """Every live process in these process groups (a server started with
    start_new_session=True and the workers it forks)."""
    pgids = {int(g) for g in pgids}
    out = []
    for pid in os.listdir("/proc"):
        if pid.isdigit():
            fields = _stat_fields(pid)
            if fields and int(fields[2]) in pgids:
                out.append(int(pid))
    return out


def process_cpu_s(pid: int) -> float:
    """User + system CPU seconds of one process (0 once it is gone)."""
    fields = _stat_fields(str(pid))
    return sum(int(x) for x in fields[11:13]) / _TICK if fields else 0.0


def group_cpu_s(pgids) -> float:
    """User + system CPU seconds of every live process in the groups, including the
    children they have waited for."""
    total = 0
    for pid in group_pids(pgids):
        fields = _stat_fields(str(pid))
        if fields:                       # utime stime cutime cstime: fields 14-17
            total += sum(int(x) for x in fields[11:15])
    return total / _TICK


def group_rss_mb(pgids) -> float:
    """Summed VmRSS of every live process in the groups, MB (forked workers share
    pages with their parent until written, so this counts shared pages twice)."""
    total = 0.0
    for pid in group_pids(pgids):
        try:
            with open(f"/proc/{pid}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1]) / 1024.0
        except OSError:
            pass
    return total


def websocket_status(port: int, origin: str | None, path: str = "/app/ws",
                     host: str | None = None, session: bool = False) -> int | None:
    """HTTP status of a websocket upgrade request sent with this Origin (and Host)
    header: 101 switches protocols, 403 is Bokeh refusing the origin, None a connection
    closed without an answer. ``session=True`` sends a session token as a page does
    (an admitted socket then opens a session instead of failing Bokeh's protocol check)."""
    key = base64.b64encode(os.urandom(16)).decode()
    lines = [f"GET {path} HTTP/1.1", f"Host: {host or f'localhost:{port}'}", "Upgrade: websocket",
             "Connection: Upgrade", f"Sec-WebSocket-Key: {key}", "Sec-WebSocket-Version: 13"]
    if session:
        import json

        payload = {"session_id": base64.urlsafe_b64encode(os.urandom(33)).decode(),
                   "session_expiry": int(time.time()) + 300}
        token = base64.urlsafe_b64encode(json.dumps(payload).encode()).decode().rstrip("=")
        lines.append(f"Sec-WebSocket-Protocol: bokeh, {token}")
    if origin is not None:
        lines.append(f"Origin: {origin}")
    with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        head = s.recv(4096)
        status = int(head.split(b"\r\n", 1)[0].split()[1]) if head else None
        if status == 101 and session:
            time.sleep(1.0)                            # let the session open, then
            s.sendall(b"\x88\x80" + os.urandom(4))     # close it (masked close frame)
            time.sleep(0.3)
        return status


# -- Bokeh client sessions ------------------------------------------------------------

def _keep_patches_while_waiting() -> None:
    """Bokeh's Python client drops every message that arrives while it waits for a
    reply (to its document pull, or a server-info request). The server may send a
    document patch in that gap (here: the first scene, computed in a worker while the
    page loads), and the client then never sees it; BokehJS in a browser keeps such
    patches (checked in Chromium: 15 of 15 loads of a link that needs a second scene
    job show it). So do the same: apply a patch at once if the document is there,
    else keep it and apply it right after the pull."""
    from bokeh.client import states

    if getattr(states.WAITING_FOR_REPLY, "_keeps_patches", False):
        return

    async def run(self, connection):
        message = await connection._pop_message()
        if message is None:
            await connection._transition_to_disconnected(
                states.DISCONNECTED(states.ErrorReason.NETWORK_ERROR))
        elif "reqid" in message.header and message.header["reqid"] == self.reqid:
            self._reply = message
            await connection._transition(states.CONNECTED_AFTER_ACK())
        else:
            if message.msgtype == "PATCH-DOC":
                session = connection._session
                if session is not None and session._document is not None:
                    session._handle_patch(message)
                else:
                    connection.__dict__.setdefault("_early_patches", []).append(message)
            await connection._next()

    states.WAITING_FOR_REPLY.run = run
    states.WAITING_FOR_REPLY._keeps_patches = True


def _flat_message_loop() -> None:
    """Bokeh's Python client handles each message by awaiting the next handler, one
    level deeper per message, so a long wait that sees a few hundred messages (a
    streamed diagram, the pings) ends in RecursionError. Handle them in a loop."""
    from bokeh.client import connection, states

    if getattr(connection.ClientConnection._handle_messages, "_flat", False):
        return

    async def _handle_messages(self):
        while True:
            message = await self._pop_message()
            if message is None:
                await self._transition_to_disconnected(
                    states.DISCONNECTED(states.ErrorReason.HTTP_ERROR, 500, "closed"))
                return
            if message.msgtype == "PATCH-DOC":
                self._session._handle_patch(message)
            if not isinstance(self._state, states.CONNECTED_AFTER_ACK):
                await self._next()
                return
            if self._until_predicate is not None and self._until_predicate():
                self._until_predicate = None
                self._loop.stop()
                return

    _handle_messages._flat = True
    connection.ClientConnection._handle_messages = _handle_messages


def open_session(url: str, args: dict | None = None, retries: int = 3):
    """A Bokeh client session on the app (the real document, its real widget models)."""
    import panel.models  # noqa: F401  (registers Panel's model types for deserialization)
    _keep_patches_while_waiting()
    _flat_message_loop()
    from bokeh.client.session import ClientSession
    from bokeh.client.util import websocket_url_for_server_url

    for attempt in range(retries):
        try:
            session = ClientSession(websocket_url=websocket_url_for_server_url(url),
                                    arguments=args or {})
            session.connect()
            # pull, then "document ready", as a browser does (and rel_light_client.py):
            # a client that announces itself first sets the diagram going before its
            # pull, and a streamed chunk both in the pulled document and in a patch
            # kept while waiting would be drawn twice
            session.pull()
            send_document_ready(session)
        except Exception:           # noqa: BLE001 - retried, then re-raised
            if attempt == retries - 1:
                raise
            time.sleep(1.0)
            continue
        for message in session._connection.__dict__.pop("_early_patches", []):
            session._handle_patch(message)
        return session


def send_document_ready(session) -> None:
    """Tell the server the page has loaded, as BokehJS does once it has rendered
    (Panel then marks the session connected and runs ``pn.state.onload`` callbacks; the
    app starts its diagram there)."""
    from bokeh.document import Document
    from bokeh.document.events import MessageSentEvent
    from bokeh.events import DocumentReady

    conn = session._connection
    event = MessageSentEvent(session._document or Document(), "bokeh_event", DocumentReady())
    conn._loop.add_callback(conn.send_message, conn._protocol.create("PATCH-DOC", [event]))


def pump(session, predicate, timeout: float = 30.0) -> bool:
    """Run the session's client loop (applying the server's patches to
    ``session.document``) until ``predicate()`` holds or ``timeout`` passes.

    The client loop only looks at the predicate after a message arrives, so a light
    server-info request is sent every 0.5 s while waiting."""
    conn = session._connection
    loop = conn._loop
    deadline = time.monotonic() + timeout
    pinging = {"on": True}

    def ping():
        if pinging["on"] and conn.connected:
            loop.add_callback(conn.send_message, conn._protocol.create("SERVER-INFO-REQ"))
            loop.call_later(0.5, ping)

    result = {"ok": False}

    def until():
        if predicate():
            result["ok"] = True
            return True
        return time.monotonic() > deadline or not conn.connected

    loop.add_callback(ping)
    conn._loop_until(until)
    pinging["on"] = False
    return result["ok"]


def by_class(doc, css_class: str):
    for m in doc.models:
        if css_class in (getattr(m, "css_classes", None) or []):
            return m
    raise KeyError(css_class)


def _tagged(doc, name: str) -> list:
    """The models carrying setting ``name``'s class: a card's slider item (a column of box
    and slider), or the bar's box and slider, each tagged."""
    return [m for m in doc.models if f"ie-w-{name}" in (getattr(m, "css_classes", None) or [])]


def slider(doc, name: str):
    """The Bokeh Slider model of setting ``name`` (in the bar, or inside a card's item)."""
    for m in _tagged(doc, name):
        for c in [m, *getattr(m, "children", [])]:
            # a Bokeh model's class, or a light client's model (rel_light_doc.py)
            if getattr(c, "__view_model__", type(c).__name__) == "Slider":
                return c
    raise KeyError(name)


def value_input(doc, name: str):
    """The input model of setting ``name``: the numeric input of an editable slider, or
    the FloatInput/IntInput/Select itself."""
    for m in _tagged(doc, name):
        if hasattr(m, "value") and type(m).__name__ != "Slider":
            return m
        for r in m.references():
            if type(r).__name__ in ("Spinner", "NumericInput"):
                return r
    raise KeyError(name)


def message_text(doc) -> str:
    """The visible text of the app's message box ('' when hidden)."""
    import html

    box = by_class(doc, "ie-message")
    if not box.visible:
        return ""
    # the model holds escaped HTML ("&lt;p&gt;...") of the escaped message text
    return html.unescape(re.sub(r"<[^>]+>", "", html.unescape(box.text or ""))).strip()


def source(doc, name: str):
    return doc.get_model_by_name(name).data_source
