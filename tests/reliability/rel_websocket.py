"""A websocket client over one blocking socket (RFC 6455: text and binary messages,
ping/pong, close; no extensions), for the light load client (rel_light_client.py).

A thread owns one socket and reads with a deadline, so a load script's many clients are
plain threads, a wait is a socket timeout, and a refused upgrade or a closed socket is
an exception at once (``SessionRefused``, ``SessionClosed``) rather than a silent wait.
"""
from __future__ import annotations

import base64
import hashlib
import os
import socket
import time

_GUID = b"258EAFA5-E914-47DA-95CA-C5AB0DC85B11"


class SessionRefused(RuntimeError):
    """The server would not open the session (page or websocket upgrade refused)."""


class SessionClosed(RuntimeError):
    """The server closed the websocket."""


class WebSocket:
    """RFC 6455 over one blocking socket: text and binary messages, ping/pong, close; no
    extensions. ``recv(deadline)`` returns None at the deadline and keeps any partial
    frame for the next call."""

    def __init__(self, host: str, port: int, path: str, headers: dict, timeout: float):
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.buf = bytearray()
        self.parts: list[bytes] = []
        self.opcode = 0
        self.closed = False
        try:
            self._handshake(host, port, path, headers, time.monotonic() + timeout)
        except BaseException:
            self.sock.close()
            raise

    def _handshake(self, host, port, path, headers, deadline) -> None:
        key = base64.b64encode(os.urandom(16)).decode()
        lines = [f"GET {path} HTTP/1.1", f"Host: {host}:{port}", "Upgrade: websocket",
                 "Connection: Upgrade", f"Sec-WebSocket-Key: {key}",
                 "Sec-WebSocket-Version: 13", *(f"{k}: {v}" for k, v in headers.items())]
        self.sock.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        while b"\r\n\r\n" not in self.buf:
            if not self._fill(deadline):
                raise TimeoutError(f"no answer to the websocket upgrade of {path}")
        head, _, rest = bytes(self.buf).partition(b"\r\n\r\n")
        self.buf = bytearray(rest)
        status_line, *fields = head.decode("latin-1").split("\r\n")
        status = int(status_line.split()[1])
        if status != 101:
            raise SessionRefused(f"websocket upgrade of {path} refused: {status_line}")
        accept = base64.b64encode(hashlib.sha1(key.encode() + _GUID).digest()).decode()
        if f"sec-websocket-accept: {accept}".lower() not in (f.lower() for f in fields):
            raise SessionRefused(f"websocket upgrade of {path}: bad Sec-WebSocket-Accept")

    def _fill(self, deadline: float) -> bool:
        """Read what the socket has (False at the deadline); raise once it is closed."""
        self.sock.settimeout(max(0.001, deadline - time.monotonic()))
        try:
            chunk = self.sock.recv(262144)
        except (socket.timeout, BlockingIOError):
            return False
        except OSError as exc:
            self.closed = True
            raise SessionClosed(f"connection lost: {exc}") from exc
        if not chunk:
            self.closed = True
            raise SessionClosed("connection closed by the server")
        self.buf += chunk
        return True

    def _frame(self):
        """One complete frame off the buffer, or None."""
        b = self.buf
        if len(b) < 2:
            return None
        n, at = b[1] & 0x7F, 2
        if n == 126:
            if len(b) < 4:
                return None
            n, at = int.from_bytes(b[2:4], "big"), 4
        elif n == 127:
            if len(b) < 10:
                return None
            n, at = int.from_bytes(b[2:10], "big"), 10
        mask = b[1] & 0x80
        end = at + (4 if mask else 0) + n
        if len(b) < end:
            return None
        payload = bytes(b[end - n:end])
        if mask:
            payload = _masked(payload, bytes(b[at:at + 4]))
        first = b[0]
        del b[:end]
        return first & 0x80, first & 0x0F, payload

    def recv(self, deadline: float):
        """The next text (str) or binary (bytes) message, or None at the deadline."""
        while True:
            frame = self._frame()
            if frame is None:
                if not self._fill(deadline):
                    return None
                continue
            fin, opcode, payload = frame
            if opcode == 0x9:
                self.send(payload, 0xA)
            elif opcode == 0x8:
                code = int.from_bytes(payload[:2], "big") if len(payload) >= 2 else None
                if not self.closed:
                    self.closed = True
                    self._send_quietly(payload[:2], 0x8)
                raise SessionClosed(f"the server closed the websocket: code {code}, "
                                    f"reason {payload[2:].decode(errors='replace')!r}")
            elif opcode in (0x0, 0x1, 0x2):
                if opcode:
                    self.opcode, self.parts = opcode, []
                self.parts.append(payload)
                if fin:
                    data = b"".join(self.parts)
                    return data.decode() if self.opcode == 0x1 else data

    def send(self, data, opcode: int = 0x1) -> None:
        payload = data.encode() if isinstance(data, str) else data
        n, key = len(payload), os.urandom(4)
        head = bytes([0x80 | opcode])
        if n < 126:
            head += bytes([0x80 | n])
        elif n < 1 << 16:
            head += bytes([0x80 | 126]) + n.to_bytes(2, "big")
        else:
            head += bytes([0x80 | 127]) + n.to_bytes(8, "big")
        try:
            self.sock.sendall(head + key + _masked(payload, key))
        except OSError as exc:
            self.closed = True
            raise SessionClosed(f"connection lost while sending: {exc}") from exc

    def _send_quietly(self, data, opcode) -> None:
        try:
            self.send(data, opcode)
        except SessionClosed:
            pass

    def close(self, wait: float = 2.0) -> None:
        """Close handshake (code 1000), then the socket."""
        try:
            if not self.closed:
                self.closed = True
                self._send_quietly((1000).to_bytes(2, "big"), 0x8)
                end = time.monotonic() + wait
                while time.monotonic() < end:      # until the server's close or EOF
                    if self.recv(end) is None:
                        break
        except SessionClosed:
            pass
        finally:
            self.sock.close()


def _masked(data: bytes, key: bytes) -> bytes:
    n = len(data)
    if not n:
        return b""
    k = int.from_bytes((key * (n // 4 + 1))[:n], "little")
    return (int.from_bytes(data, "little") ^ k).to_bytes(n, "little")
