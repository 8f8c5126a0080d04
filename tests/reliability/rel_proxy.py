"""scripts/nginx.conf run for real: Debian's nginx on a loopback port in front of two
``panel serve app/app.py`` processes, as a deployment beyond one process would be.

The config is used as written except for four things a test must move: the listen port,
the two backend addresses and the server name (``localhost`` here). nginx runs in the
foreground with its own prefix directory (pid, access log, temp files), never as the
system service, and stops with its process group.
"""
from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path

from rel_server import ROOT, Served, free_port

NGINX_CONF = ROOT / "scripts" / "nginx.conf"


def nginx_binary() -> str | None:
    return shutil.which("nginx") or next(
        (p for p in ("/usr/sbin/nginx",) if os.access(p, os.X_OK)), None)


def loopback_config(text: str, listen: int, backends: list[int],
                    server_name: str = "localhost") -> str:
    """The deployment config moved onto loopback ports; each replacement must apply."""
    swaps = [("listen 8080", f"listen 127.0.0.1:{listen}", 2),
             ("server 127.0.0.1:5006;", f"server 127.0.0.1:{backends[0]};", 1),
             ("server 127.0.0.1:5007;", f"server 127.0.0.1:{backends[1]};", 1),
             ("server_name classroom.example;", f"server_name {server_name};", 1)]
    for old, new, count in swaps:
        if text.count(old) != count:
            raise ValueError(f"scripts/nginx.conf: expected {count} x {old!r}")
        text = text.replace(old, new)
    return text


class Proxy:
    """nginx with the project's config, listening on 127.0.0.1:<port>."""

    def __init__(self, port: int, backends: list[int], start_timeout: float = 30.0,
                 text: str | None = None):
        exe = nginx_binary()
        if exe is None:
            raise RuntimeError("nginx is not installed (apt-get install nginx-light)")
        self.port = port
        self.prefix = Path(tempfile.mkdtemp(prefix="impact-nginx-"))
        self.prefix.chmod(0o755)            # workers run as nobody when started as root
        for d in ("tmp", "logs"):
            (self.prefix / d).mkdir()
        self.conf = self.prefix / "nginx.conf"
        self.conf.write_text(loopback_config(text or NGINX_CONF.read_text(), port, backends))
        self.cmd = [exe, "-p", f"{self.prefix}/", "-e", "stderr", "-c", str(self.conf),
                    "-g", "daemon off;"]
        self.log_path = self.prefix / "nginx.stderr"
        with open(self.log_path, "wb") as out:
            self.proc = subprocess.Popen(self.cmd, stdout=out, stderr=subprocess.STDOUT,
                                         start_new_session=True)
        deadline = time.monotonic() + start_timeout
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if self.proc.poll() is not None or time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError(f"nginx did not start:\n{self.log_path.read_text()}")
                time.sleep(0.1)

    def access_log(self) -> list[dict]:
        """Each request: request line, status, backend address and route key."""
        pattern = re.compile(r'"(?P<request>[^"]*)" (?P<status>\d+) '
                             r'backend=(?P<backend>\S+) route=(?P<route>\S+)')
        path = self.prefix / "access.log"
        text = path.read_text() if path.exists() else ""
        return [m.groupdict() for m in map(pattern.search, text.splitlines()) if m]

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)   # nginx: fast shutdown
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
        shutil.rmtree(self.prefix, ignore_errors=True)


class ProxiedApp:
    """Two app processes behind the proxy; ``url`` is the page as browsers open it."""

    def __init__(self, log_name: str = "proxied", extra_args=()):
        self.port = free_port()
        origin = f"localhost:{self.port}"    # the proxy's address: what browsers send
        self.backends: list[Served] = []
        try:
            for i in range(2):
                self.backends.append(Served(f"{log_name}-{i}.log", extra_args=list(extra_args),
                                            origin=origin))
            self.proxy = Proxy(self.port, [b.port for b in self.backends])
        except Exception:
            self.stop()
            raise
        self.base = f"http://localhost:{self.port}"
        self.url = f"{self.base}/app"

    @property
    def pgids(self) -> list[int]:
        return [b.proc.pid for b in self.backends]

    def bad_log_lines(self, offsets=None) -> list[str]:
        offsets = offsets or [0] * len(self.backends)
        return [line for b, o in zip(self.backends, offsets) for line in b.bad_log_lines(o)]

    def stop(self) -> None:
        if getattr(self, "proxy", None) is not None:
            self.proxy.stop()
        for b in self.backends:
            b.stop()
