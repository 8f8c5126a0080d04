"""Where Numba keeps the compiled kernels when the package is installed.

Numba writes its cache beside the source (``__pycache__``).  In a source checkout that is
what a developer expects; in an installed package it would write into site-packages. So
when impactlib is imported from a site-packages (or dist-packages) directory and
``NUMBA_CACHE_DIR`` is not set, the cache goes to the user's cache directory instead:
``$XDG_CACHE_HOME/impactlib/numba`` (default ``~/.cache/impactlib/numba``; on Windows
``%LOCALAPPDATA%\\impactlib\\numba``, on macOS ``~/Library/Caches/impactlib/numba``).
A ``NUMBA_CACHE_DIR`` set by the user (or the Dockerfile) always wins.

Numba checks a cached kernel against its own file only, not against the kernels it
calls in other files, so an edited callee would run stale.  The cache is therefore tied
to a hash of every jitted source of the package: installed, it lives in a subdirectory
named by the hash; in a checkout, the cache files beside the sources are dropped when
the hash differs from the one they were written under.
"""
from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent


def installed(package_dir: Path = PACKAGE_DIR) -> bool:
    """Whether the package lives in an installed-packages directory (not a checkout)."""
    return any(part in ("site-packages", "dist-packages") for part in package_dir.parts)


def user_cache_dir() -> Path:
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "impactlib" / "numba"


def sources_hash(package_dir: Path = PACKAGE_DIR) -> str:
    """A hash of every module of the package that defines a jitted function or an
    overload (a function jitted code calls)."""
    h = hashlib.sha1()
    for path in sorted(package_dir.rglob("*.py")):
        text = path.read_bytes()
        if b"@jit" in text or b"@overload" in text:
            h.update(path.relative_to(package_dir).as_posix().encode() + b"\0" + text)
    return h.hexdigest()[:16]


def drop_stale(package_dir: Path = PACKAGE_DIR, digest: str | None = None) -> bool:
    """In a checkout: remove the cache files beside the sources when they were written
    under other sources (a missing stamp counts as other); True if it removed any."""
    digest = digest or sources_hash(package_dir)
    stamp = package_dir / "__pycache__" / "numba-sources.txt"
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    dropped = False
    for f in package_dir.rglob("__pycache__/*.nb[ic]"):
        try:
            f.unlink()
            dropped = True
        except OSError:          # another process removed it, or a read-only checkout
            pass
    try:
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest)
    except OSError:
        pass
    return dropped


def configure() -> str | None:
    """Point Numba's cache at the user cache directory for an installed package (before
    any kernel is compiled); return the directory chosen, None when left to Numba."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    if not installed():
        drop_stale()
        return None
    path = str(user_cache_dir() / sources_hash())
    os.environ["NUMBA_CACHE_DIR"] = path
    config = sys.modules.get("numba.core.config")
    if config is not None:   # numba already imported: its config read the variable already
        config.CACHE_DIR = path
    return path


configure()
