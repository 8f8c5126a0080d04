"""Numba's on-disk cache checks a kernel against its own file only; impactlib.numba_cache
ties it to every jitted source, so an edit to a callee in another file is never run
stale (a fresh copy of the package, two processes, one edit in between)."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import impactlib

CALL = ("import impactlib.kernels.entry as e; "
        "print(e.run_constants(1.0, 0.05, 1.0, 0.0, 0.8, 2.0)[1])")


def _rate(root: Path) -> str:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "IMPACTLIB_NO_CACHE",
                                                              "NUMBA_DISABLE_JIT")}
    env["PYTHONPATH"] = str(root)
    out = subprocess.run([sys.executable, "-c", CALL], cwd=root, env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_an_edited_callee_in_another_file_is_not_run_from_the_cache(tmp_path):
    src = Path(impactlib.__file__).parent
    pkg = tmp_path / "impactlib"
    shutil.copytree(src, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    # run_constants (entry.py) calls fastest_rate (flight.py): at the paper defaults it
    # returns omega = 2
    assert float(_rate(tmp_path)) == 2.0
    assert list(pkg.rglob("__pycache__/entry.run_constants*.nbi")), "nothing was cached"
    flight = pkg / "kernels" / "flight.py"
    text = flight.read_text()
    old = "    return max(max(lam, sp[OM]), sp[C_] / sp[M])\n"
    assert old in text
    flight.write_text(text.replace(old, "    return 3.0 * max(max(lam, sp[OM]), sp[C_] / sp[M])\n"))
    # entry.py is unchanged, so without the package's own check Numba would load its
    # cached run_constants, with the old fastest_rate compiled in
    assert float(_rate(tmp_path)) == 6.0
