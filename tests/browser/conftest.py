"""A served app on a free loopback port, and Debian's Chromium for pytest-playwright."""
import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "test-results"
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]


def pytest_collection_modifyitems(items):
    for item in items:
        if "tests/browser" in str(item.fspath):
            item.add_marker(pytest.mark.browser)
            if not Path(CHROMIUM).exists():
                item.add_marker(pytest.mark.skip(reason=f"{CHROMIUM} is not installed"))


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args):
    return {**browser_type_launch_args, "executable_path": CHROMIUM, "headless": True,
            "args": CHROMIUM_ARGS}


@pytest.fixture(scope="session")
def browser_context_args(browser_context_args):
    return {**browser_context_args, "viewport": {"width": 1400, "height": 1000}}


#: A line of the served app's log that a browser test must not cause: a Python logging
#: record (Bokeh's, Tornado's, param's, the app's) at WARNING or above, or a traceback.
BAD_LINE = re.compile(r"\b(WARNING|ERROR|CRITICAL)\b|Traceback")


def bad_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if BAD_LINE.search(line)]


@pytest.fixture(autouse=True)
def clean_server_log(request):
    """A test that uses the served app fails on any warning or error the server logs
    while it runs (lines logged between tests are charged to the next one)."""
    if "server" not in request.fixturenames:
        yield
        return
    log = request.getfixturevalue("server").log
    start = log.stat().st_size
    yield
    with open(log, "rb") as f:
        f.seek(start)
        new = f.read().decode("utf-8", "replace")
    bad = bad_lines(new)
    assert not bad, "the server logged:\n" + "\n".join(bad[:20])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="session")
def server(delete_output_dir, tmp_path_factory):
    """``panel serve app/app.py`` as a user runs it, on 127.0.0.1:<free port>.

    Yields an object with ``url`` (the /app page) and ``log`` (path of the server's
    combined stdout/stderr)."""
    import impactlib as il

    # the kernels compiled first, as scripts/app.sh does before serving: a cold compile
    # inside the first session's diagram would count against its time limit
    il.warmup()
    port = _free_port()
    # Not in test-results/: pytest-playwright empties that folder when a session starts.
    log = tmp_path_factory.mktemp("server") / "server.log"
    panel = Path(sys.executable).with_name("panel")
    cmd = [str(panel), "serve", "app/app.py", "--address", "127.0.0.1", "--port", str(port),
           "--allow-websocket-origin", f"127.0.0.1:{port}"]
    with open(log, "wb") as out:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT,
                                start_new_session=True)
    url = f"http://127.0.0.1:{port}/app"
    deadline = time.monotonic() + 90
    while True:
        try:
            with urllib.request.urlopen(url, timeout=5) as r:
                if r.status == 200:
                    break
        except OSError:
            pass
        if proc.poll() is not None or time.monotonic() > deadline:
            os.killpg(proc.pid, signal.SIGKILL)
            pytest.fail(f"server did not start; log:\n{log.read_text()[-3000:]}")
        time.sleep(0.3)

    class Server:
        pass
    srv = Server()
    srv.url, srv.log, srv.proc = url, log, proc
    yield srv
    os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(10)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "browser-server.log").write_bytes(log.read_bytes())
