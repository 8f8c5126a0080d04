"""The documentation runs: the Sphinx build (API reference from the docstrings, the
guides) with warnings as errors, and every example notebook executed top to bottom (each
checks what it shows against the paper's or a closed-form statement)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((REPO / "docs" / "notebooks").glob("*.ipynb"))

pytestmark = pytest.mark.slow


def test_sphinx_build_without_warnings(tmp_path):
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                          "html", str(REPO / "docs"), str(tmp_path / "html")],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    api = (tmp_path / "html" / "api" / "index.html").read_text()
    for name in ("simulate", "Solution", "to_xarray", "regime_map", "continuation"):
        assert name in api, name


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 4


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")
    # the kernel imports the app as the installed package does (impact_explorer), from
    # this checkout's app/ (ahead of any installed copy)
    shim = tmp_path / "packages"
    shim.mkdir()
    (shim / "impact_explorer").symlink_to(REPO / "app", target_is_directory=True)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(shim), str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])]))
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors, errors
    if path.stem == "app_in_jupyter":    # its last check printed what it saw
        text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                       for o in c.get("outputs", []))
        assert "all applied on the kernel's thread (MainThread)" in text, text
