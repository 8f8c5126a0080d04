"""A loopback TCP relay that can drop every connection and refuse new ones for a while:
a classroom's Wi-Fi going away and coming back, between a browser and the server."""
from __future__ import annotations

import socket
import threading
import time


class Relay:
    """Forward 127.0.0.1:<port> to ``target`` (host, port), byte for byte.

    ``cut()`` closes every open connection (both ends see the TCP connection end) and
    closes new ones at once until ``restore()``. ``cut_mid_message()`` arms a cut that
    happens inside the first websocket message the server starts after the browser has
    next sent something: its first frame reaches the browser, the rest never does.
    ``wait_quiet()`` waits until the server has sent nothing for a while, so that the
    next message it starts is an answer to the browser.
    """

    def __init__(self, target: tuple[str, int]):
        self.target = target
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self._lock = threading.Lock()
        self._open: list[socket.socket] = []
        self._down = False
        self.accepted = 0
        self.refused = 0
        self._armed = False
        self._spoke = False               # the browser sent something since arming
        self._last_down = time.monotonic()
        self.cut_after = None             # the first frame forwarded before an armed cut
        threading.Thread(target=self._accept, daemon=True, name="relay-accept").start()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self.listener.accept()
            except OSError:
                return
            with self._lock:
                if self._down:
                    self.refused += 1
                    client.close()
                    continue
                self.accepted += 1
            try:
                upstream = socket.create_connection(self.target, timeout=10)
                upstream.settimeout(None)
            except OSError:
                client.close()
                continue
            with self._lock:
                self._open += [client, upstream]
            threading.Thread(target=self._pump, args=(client, upstream), daemon=True).start()
            threading.Thread(target=self._pump, args=(upstream, client, _Frames()),
                             daemon=True).start()

    def cut_mid_message(self) -> None:
        self._spoke = False
        self._armed = True

    def wait_quiet(self, seconds: float, timeout: float = 30.0) -> None:
        """Return once the server has sent nothing for ``seconds``; raise after ``timeout``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() - self._last_down < seconds:
            if time.monotonic() > deadline:
                raise TimeoutError(f"the server kept sending for {timeout} s")
            time.sleep(0.05)

    def _pump(self, src: socket.socket, dst: socket.socket, frames=None) -> None:
        try:
            while data := src.recv(65536):
                if frames is None:                         # browser -> server
                    dst.sendall(data)
                    self._spoke = self._armed
                    continue
                self._last_down = time.monotonic()
                if self._armed and self._spoke and frames.since is None:
                    frames.since = frames.seen
                frames.feed(data)
                if (self._armed and frames.since is not None
                        and frames.message_start is not None
                        and frames.message_start_at >= frames.since):
                    # one frame of a message, then the link goes
                    keep = frames.message_start_end - (frames.seen - len(data))
                    if 0 < keep <= len(data):
                        dst.sendall(data[:keep])
                        self._armed = False
                        self.cut_after = frames.message_start
                        self.cut()
                        return
                dst.sendall(data)
        except OSError:
            pass
        for s in (src, dst):
            try:
                s.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass

    def cut(self) -> None:
        with self._lock:
            self._down = True
            sockets, self._open = self._open, []
        for s in sockets:
            try:
                s.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            s.close()

    def restore(self) -> None:
        with self._lock:
            self._down = False

    def close(self) -> None:
        self.cut()
        self.listener.close()


class _Frames:
    """Frame boundaries of a server's websocket stream (RFC 6455; server frames are not
    masked), after the HTTP upgrade response. ``message_start`` is the first frame of
    the latest Bokeh message (a text frame holding its header), ``message_start_at`` and
    ``message_start_end`` its start and end as byte offsets in the stream; ``seen``
    counts the bytes fed; ``since`` is an offset set by the relay (see ``Relay``)."""

    def __init__(self):
        self.buf = b""
        self.seen = 0
        self.offset = None                # stream offset of ``buf[0]`` once in frames
        self.message_start = None
        self.message_start_at = None
        self.message_start_end = None
        self.since = None

    def feed(self, data: bytes) -> None:
        self.seen += len(data)
        self.buf += data
        if self.offset is None:
            end = self.buf.find(b"\r\n\r\n")
            if end < 0:
                return
            if not self.buf.startswith(b"HTTP/1.1 101"):
                self.buf, self.offset = b"", float("inf")     # plain HTTP: no frames
                return
            self.offset = self.seen - len(self.buf) + end + 4
            self.buf = self.buf[end + 4:]
        while len(self.buf) >= 2 and self.offset != float("inf"):
            n, head = self.buf[1] & 0x7F, 2
            if n == 126:
                if len(self.buf) < 4:
                    return
                n, head = int.from_bytes(self.buf[2:4], "big"), 4
            elif n == 127:
                if len(self.buf) < 10:
                    return
                n, head = int.from_bytes(self.buf[2:10], "big"), 10
            if len(self.buf) < head + n:
                return
            payload = self.buf[head:head + n]
            if self.buf[0] & 0x0F == 1 and payload.startswith(b'{"msgid"'):
                self.message_start = payload[:80]
                self.message_start_at = self.offset
                self.message_start_end = self.offset + head + n
            self.offset += head + n
            self.buf = self.buf[head + n:]
