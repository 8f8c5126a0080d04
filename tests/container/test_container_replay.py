"""Replay the Dockerfile's install steps in a fresh venv, then serve the app from it.

No container engine runs here, so this test does what the image build does, step by
step, read from the Dockerfile itself: ENV, ARG and WORKDIR are followed with every
absolute path moved under a temporary root (/opt/venv -> ROOT/opt/venv, ...); COPY is
copied from the repository (without caches); every RUN that installs or warms (pip,
venv, impactlib) runs through /bin/sh exactly as written, with Debian's python3 first
on PATH as in the image. RUNs that need root (apt-get, groupadd/useradd) are not run;
only the directories they create (`install -d`) are made. One deliberate difference:
`--no-cache-dir` is dropped so repeated runs reuse pip's cache. Then the CMD runs as
written, moved to a free loopback port (start_new_session, stopped with os.killpg), and
/liveness, /app and the HEALTHCHECK command must answer with a clean server log.

What this does not show: the apt-get step, the non-root user, file ownership and
permissions, the read-only root and the image as a whole; scripts/container_check.sh
exercises those with podman.
"""

from __future__ import annotations

import base64
import json
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
import tomllib
import urllib.error
import urllib.request
from pathlib import Path

import pytest

import dockerfile_spec as spec

pytestmark = [pytest.mark.slow, pytest.mark.timeout(1500)]

# RUN steps made only of these commands set up the system and need root: not replayed.
SYSTEM_COMMANDS = {"apt-get", "groupadd", "useradd", "install", "rm"}
# Host variables that would leak into the replayed build or server.
LEAKY = ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONUSERBASE")
LEAKY_PREFIXES = ("NUMBA_", "BOKEH_", "PANEL_", "IMPACT_", "MPL")
STARTUP_TIMEOUT = 240.0


def commands(run_args: str) -> list[list[str]]:
    lexer = shlex.shlex(run_args, posix=True, punctuation_chars=";&|")
    lexer.whitespace_split = True
    out: list[list[str]] = [[]]
    for token in lexer:
        if token in (";", "&&", "||", "|", "&"):
            out.append([])
        else:
            out[-1].append(token)
    return [c for c in out if c]


def is_system_step(run_args: str) -> bool:
    return all(c[0] in SYSTEM_COMMANDS for c in commands(run_args))


def debian_python() -> str:
    """The interpreter the image uses (Debian's python3 with venv), if this host has it."""
    exe = "/usr/bin/python3"
    if Path(exe).exists():
        ok = subprocess.run([exe, "-c", "import ensurepip, venv"], capture_output=True)
        if ok.returncode == 0:
            return exe
    return getattr(sys, "_base_executable", sys.executable)


def host_env() -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in LEAKY and not k.startswith(LEAKY_PREFIXES)
    }
    return env


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def get(url: str, timeout: float = 30.0) -> tuple[int, str]:
    try:
        with urllib.request.urlopen(url, timeout=timeout) as r:
            return r.status, r.read().decode("utf-8", "replace")
    except urllib.error.HTTPError as e:
        body = e.read().decode("utf-8", "replace")
        e.close()
        return e.code, body


def copy_context(step: spec.Step, root: Path) -> None:
    words = shlex.split(step.instruction.args)
    srcs, dest_raw = [w for w in words[:-1] if not w.startswith("--")], words[-1]
    dest = spec.expand(str(root) + dest_raw if dest_raw.startswith("/") else dest_raw, step.env)
    if not Path(dest).is_absolute():
        dest = str(Path(step.workdir) / dest)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")
    for src in srcs:
        path = spec.REPO / src
        assert path.exists(), f"COPY {src}: missing from the repository (the build would fail)"
        if path.is_dir():
            shutil.copytree(path, dest, ignore=ignore, dirs_exist_ok=True)
        else:
            Path(dest).mkdir(parents=True, exist_ok=True)
            shutil.copy2(path, Path(dest) / path.name)


def make_dirs(step: spec.Step) -> None:
    """Make what `install -d` would, without the owner (the replay is not root)."""
    for c in commands(step.instruction.args):
        if c[:2] != ["install", "-d"]:
            continue
        args, k = c[2:], 0
        while k < len(args):
            if args[k] in ("-o", "-g", "-m"):
                k += 2
                continue
            Path(spec.expand(args[k], step.env)).mkdir(parents=True, exist_ok=True)
            k += 1


@pytest.fixture(scope="module")
def replay(tmp_path_factory):
    base = tmp_path_factory.mktemp("container-replay")
    root = base / "root"
    log = base / "build.log"
    python = debian_python()
    shim = base / "shim"
    shim.mkdir()
    (shim / "python3").symlink_to(python)
    hosts = host_env()
    base_env = {"PATH": f"{shim}:{hosts.get('PATH', spec.BASE_PATH)}"}

    def rewrite(value: str) -> str:
        return str(root) + value

    steps = list(spec.walk(spec.parse(spec.DOCKERFILE.read_text()), rewrite, base_env))
    replayed = []
    with log.open("w") as out:
        for step in steps:
            ins = step.instruction
            if ins.keyword == "COPY":
                copy_context(step, root)
            elif ins.keyword == "RUN" and is_system_step(ins.args):
                make_dirs(step)
            elif ins.keyword == "RUN":
                assert not re.search(r"""(^|[\s"'=])/(?!dev/null)""", ins.args), (
                    f"line {ins.line}: a replayed RUN must name paths through ENV/ARG variables"
                )
                command = ins.args.replace("--no-cache-dir", "")
                cwd = Path(step.workdir)
                cwd.mkdir(parents=True, exist_ok=True)
                out.write(f"\n### line {ins.line}: RUN {command}\n")
                out.flush()
                t0 = time.perf_counter()
                run = subprocess.run(
                    ["/bin/sh", "-c", command],
                    cwd=cwd,
                    env=hosts | step.env,
                    stdout=out,
                    stderr=subprocess.STDOUT,
                    timeout=1200,
                )
                out.write(f"### exit {run.returncode} after {time.perf_counter() - t0:.1f} s\n")
                out.flush()
                assert run.returncode == 0, (
                    f"Dockerfile line {ins.line} failed in the replay:\n" + log.read_text()[-6000:]
                )
                replayed.append(ins.line)
    final = steps[-1]
    assert final.instruction.keyword == "CMD"
    env = hosts | final.env
    yield {
        "root": root,
        "env": env,
        "workdir": Path(final.workdir),
        "venv": Path(env["VIRTUAL_ENV"]),
        "cmd": spec.serve_command([s.instruction for s in steps]),
        "healthcheck": next(
            spec.healthcheck_command(s.instruction) for s in steps if s.instruction.keyword == "HEALTHCHECK"
        ),
        "replayed": replayed,
        "python": python,
        "log": log,
    }
    shutil.rmtree(base, ignore_errors=True)  # about 750 MB


def cache_files(env: dict[str, str]) -> dict[str, tuple[int, int]]:
    cache = Path(env["NUMBA_CACHE_DIR"])
    return {
        str(p.relative_to(cache)): (p.stat().st_size, p.stat().st_mtime_ns)
        for p in cache.rglob("*")
        if p.is_file()
    }


@pytest.fixture(scope="module")
def served(replay):
    port = free_port()
    shell = replay["cmd"]
    assert shell[:2] == ["/bin/sh", "-c"], shell
    script = shell[2]
    for old in ("--address 0.0.0.0", f"--port {spec.PORT}"):
        assert script.count(old) == 1, f"CMD should hold {old!r} once"
    script = script.replace("--address 0.0.0.0", "--address 127.0.0.1")
    script = script.replace(f"--port {spec.PORT}", f"--port {port}")
    env = replay["env"] | {"IMPACT_ALLOWED_ORIGINS": f"localhost:{port}"}
    log = replay["root"].parent / "server.log"
    before = cache_files(env)
    with log.open("w") as out:
        proc = subprocess.Popen(
            ["/bin/sh", "-c", script],
            cwd=replay["workdir"],
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        try:
            deadline = time.monotonic() + STARTUP_TIMEOUT
            while True:
                assert proc.poll() is None, "server exited:\n" + log.read_text()[-4000:]
                try:
                    if get(f"http://127.0.0.1:{port}/liveness", timeout=5)[0] == 200:
                        break
                except OSError:
                    pass
                assert time.monotonic() < deadline, "no /liveness:\n" + log.read_text()[-4000:]
                time.sleep(0.5)
            yield {"port": port, "log": log, "proc": proc, "cache_before": before, "env": env}
        finally:
            try:
                os.killpg(proc.pid, signal.SIGTERM)
                proc.wait(timeout=20)
            except ProcessLookupError:
                pass
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(timeout=20)


def test_replay_ran_the_install_and_warmup_steps(replay):
    assert len(replay["replayed"]) >= 2, replay["replayed"]  # pip install, cache warm-up


def test_installed_versions_are_the_pinned_ones(replay):
    # the runtime dependencies of pyproject.toml, at the versions scripts/constraints.txt pins
    pyproject = tomllib.loads((spec.REPO / "pyproject.toml").read_text())
    names = [re.split(r"[<>=!~ ;\[]", d, maxsplit=1)[0].lower() for d in pyproject["project"]["dependencies"]]
    lines = (spec.REPO / "scripts" / "constraints.txt").read_text().splitlines()
    locked = dict(ln.split("==") for ln in lines if "==" in ln and not ln.startswith("#"))
    locked = {n.lower().replace("_", "-"): v for n, v in locked.items()}
    pins = {n: locked[n] for n in names}
    assert pins, "pyproject.toml declares no dependency"
    python = replay["venv"] / "bin" / "python"
    code = (
        "import importlib.metadata as m, json, sys; "
        "print(json.dumps({n: m.version(n) for n in sys.argv[1:]}))"
    )
    run = subprocess.run(
        [python, "-P", "-c", code, *pins], capture_output=True, text=True, env=replay["env"], timeout=120
    )
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout) == pins
    check = subprocess.run(
        [python, "-m", "pip", "check"], capture_output=True, text=True, env=replay["env"], timeout=120
    )
    assert check.returncode == 0, check.stdout + check.stderr


def test_impactlib_comes_from_the_venv_not_the_checkout(replay):
    run = subprocess.run(
        [replay["venv"] / "bin" / "python", "-P", "-c", "import impactlib; print(impactlib.__file__)"],
        capture_output=True,
        text=True,
        cwd=replay["workdir"],
        env=replay["env"],
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert Path(run.stdout.strip()).is_relative_to(replay["venv"]), run.stdout


def test_warmup_filled_the_numba_cache(replay):
    files = cache_files(replay["env"])
    assert any(f.endswith(".nbi") for f in files) and any(f.endswith(".nbc") for f in files), files


def test_liveness_and_page_answer(served):
    base = f"http://127.0.0.1:{served['port']}"
    status, body = get(f"{base}/liveness")
    assert status == 200, body
    status, body = get(f"{base}/app", timeout=120)
    assert status == 200, body[:2000]
    assert "bokeh" in body.lower()
    # Builds one app document on the server: a page that would render blank fails here.
    status, body = get(f"{base}/liveness?endpoint=/app", timeout=120)
    assert status == 200, body[:2000]


def test_the_healthcheck_command_passes(replay, served):
    cmd = replay["healthcheck"]
    cmd = [replay["venv"] / "bin" / cmd[0]] + [
        w.replace(f":{spec.PORT}/", f":{served['port']}/") for w in cmd[1:]
    ]
    run = subprocess.run(cmd, capture_output=True, text=True, env=served["env"], timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr


def websocket_status(port: int, origin: str) -> int:
    """HTTP status of a websocket upgrade on /app/ws sent with this Origin and a valid
    unsigned Bokeh session token (as a browser's page would send), then hung up."""
    payload = {"session_id": base64.urlsafe_b64encode(os.urandom(33)).decode(),
               "session_expiry": int(time.time()) + 300}
    token = base64.urlsafe_b64encode(json.dumps(payload).encode()).decode().rstrip("=")
    key = base64.b64encode(os.urandom(16)).decode()
    request = (
        f"GET /app/ws HTTP/1.1\r\nHost: localhost:{port}\r\nUpgrade: websocket\r\n"
        f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
        f"Sec-WebSocket-Protocol: bokeh, {token}\r\nOrigin: {origin}\r\n\r\n"
    )
    with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
        s.sendall(request.encode())
        status = int(s.recv(4096).split(b"\r\n", 1)[0].split()[1])
        if status == 101:
            time.sleep(2)  # let the server open the session before the client leaves
            s.sendall(b"\x88\x80" + os.urandom(4))  # masked close frame, no payload
            time.sleep(0.5)
        return status


def test_websocket_admits_only_the_configured_origin(served):
    port = served["port"]
    assert websocket_status(port, "http://evil.example") == 403
    assert websocket_status(port, f"http://evil.example:{port}") == 403
    assert websocket_status(port, f"http://localhost:{port}") == 101


def test_first_pages_compile_nothing_the_build_did_not_cache(served):
    """The warm-up must cover what a page needs: serving compiles nothing new."""
    base = f"http://127.0.0.1:{served['port']}"
    assert get(f"{base}/app", timeout=120)[0] == 200
    time.sleep(5)  # let work started by the sessions (diagram chunks) reach its kernels
    after = cache_files(served["env"])
    changed = sorted(k for k in after if served["cache_before"].get(k) != after[k])
    assert not changed, f"Numba compiled at serve time (extend the build's warm-up): {changed}"


def test_server_log_has_no_traceback(served):
    time.sleep(1)
    text = served["log"].read_text()
    assert served["proc"].poll() is None, text[-4000:]
    assert "Traceback" not in text, text[-6000:]
    assert not re.search(r"^(ERROR|CRITICAL)", text, flags=re.M), text[-6000:]
