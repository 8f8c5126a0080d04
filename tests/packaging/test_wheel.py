"""The built wheel, installed into a fresh venv outside the checkout, as a researcher
would get it: the package names it installs, a short simulation from there (same numbers
as the checkout, the Numba cache in the user's cache directory, not site-packages), the
command line, and `impact-explorer serve` answering its health check and the page.

The fresh venv gets the dependencies through a .pth line naming this venv's site-packages
(no download; that directory's own .pth files, the checkout's editable install among
them, are not processed), and the wheel with --no-deps.
"""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import sysconfig
import time
import urllib.request
import zipfile
from pathlib import Path

import numpy as np
import pytest

import impactlib as il

pytestmark = [pytest.mark.slow, pytest.mark.timeout(1200)]
REPO = Path(__file__).resolve().parents[2]


def _env(tmp: Path) -> dict:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("NUMBA_", "PYTHON", "VIRTUAL_ENV", "IMPACT", "BOKEH_", "PANEL_"))}
    env["XDG_CACHE_HOME"] = str(tmp / "user-cache")
    env["HOME"] = str(tmp / "home")
    return env


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("wheel")
    dist = tmp / "dist"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w",
                            str(dist), str(REPO)], capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stdout + build.stderr
    wheel = next(dist.glob("impact_explorer-*.whl"))
    venv = tmp / "fresh"
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    site = Path(subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    (site / "zz_project_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    inst = subprocess.run([py, "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)],
                          capture_output=True, text=True, timeout=600)
    assert inst.returncode == 0, inst.stdout + inst.stderr
    work = tmp / "elsewhere"
    work.mkdir()
    return {"tmp": tmp, "wheel": wheel, "venv": venv, "py": py, "site": site, "work": work,
            "env": _env(tmp)}


def _source_packages() -> set[str]:
    """Every package folder of the checkout under the name the wheel gives it."""
    out = set()
    for top, name in (("impactlib", "impactlib"), ("app", "impact_explorer")):
        for init in (REPO / top).rglob("__init__.py"):
            rel = init.parent.relative_to(REPO / top).parts
            out.add(".".join((name, *rel)))
    return out


def test_wheel_holds_every_package_under_its_own_names_only(installed):
    names = zipfile.ZipFile(installed["wheel"]).namelist()
    top = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert top == {"impactlib", "impact_explorer"}, top
    packages = {str(Path(n).parent).replace("/", ".") for n in names if n.endswith("/__init__.py")}
    assert packages == _source_packages()


def test_no_generic_app_module_in_the_fresh_venv(installed):
    run = subprocess.run([installed["py"], "-P", "-c", "import app"], capture_output=True,
                         text=True, cwd=installed["work"], env=installed["env"], timeout=120)
    assert run.returncode != 0 and "No module named 'app'" in run.stderr, run.stderr


def test_simulation_from_the_installed_wheel(installed):
    code = ("import json, impactlib as il; s = il.simulate(il.Params(), t_end=100.0, t_record=50.0); "
            "print(json.dumps({'file': il.__file__, 'version': il.__version__, "
            "'t': s.impacts.t.tolist(), 'v': s.impacts.v.tolist()}))")
    run = subprocess.run([installed["py"], "-P", "-c", code], capture_output=True, text=True,
                         cwd=installed["work"], env=installed["env"], timeout=600)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    assert Path(got["file"]).is_relative_to(installed["site"]), got["file"]
    assert got["version"] == il.__version__
    here = il.simulate(il.Params(), t_end=100.0, t_record=50.0)
    # the same code on the same machine: bit for bit
    assert np.array_equal(got["t"], here.impacts.t) and np.array_equal(got["v"], here.impacts.v)
    # Numba's cache went to the user cache directory, nothing into site-packages
    cache = Path(installed["env"]["XDG_CACHE_HOME"]) / "impactlib" / "numba"
    assert any(cache.rglob("*.nbi")), "no Numba cache in the user cache directory"
    assert not any(installed["site"].rglob("*.nbi")), "Numba cache written into site-packages"


def test_command_line_from_the_installed_wheel(installed):
    out = installed["work"] / "sol.csv"
    run = subprocess.run([installed["venv"] / "bin" / "impactlib", "simulate", "--t-end", "100",
                          "--t-record", "50", "--out", str(out)], capture_output=True, text=True,
                         cwd=installed["work"], env=installed["env"], timeout=600)
    assert run.returncode == 0, run.stderr
    settings, cols = il.io.read_csv(out)
    here = il.simulate(il.Params(), t_end=100.0, t_record=50.0)
    assert settings["version"] == il.__version__ and settings["t_end"] == "100.0"
    assert np.array_equal(cols["v"], here.impacts.v)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url, timeout=10.0):
    with urllib.request.urlopen(url, timeout=timeout) as r:
        return r.status, r.read().decode("utf-8", "replace")


def test_serve_from_the_installed_wheel(installed):
    port = _free_port()
    log = installed["tmp"] / "serve.log"
    with log.open("w") as out:
        proc = subprocess.Popen([installed["venv"] / "bin" / "impact-explorer", "serve", "--port",
                                 str(port), "--address", "127.0.0.1"], stdout=out,
                                stderr=subprocess.STDOUT, cwd=installed["work"],
                                env=installed["env"], start_new_session=True)
    try:
        deadline = time.monotonic() + 240
        while True:
            try:
                status, _ = _get(f"http://127.0.0.1:{port}/liveness", timeout=5)
                break
            except OSError:
                assert proc.poll() is None, log.read_text()
                assert time.monotonic() < deadline, log.read_text()
                time.sleep(0.5)
        assert status == 200
        status, body = _get(f"http://127.0.0.1:{port}/app", timeout=300)
        assert status == 200 and "Impact Explorer" in body
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=30)
    text = log.read_text()
    assert "Traceback" not in text and "ERROR" not in text, text
