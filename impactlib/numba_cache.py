"""Where Numba keeps the compiled kernels when the package is installed.

Numba writes its cache beside the source (``__pycache__``).  In a source checkout that is
what a developer expects; in an installed package it would write into site-packages. So
when impactlib is imported from a site-packages (or dist-packages) directory and
``NUMBA_CACHE_DIR`` is not set, the cache goes to the user's cache directory instead:
``$XDG_CACHE_HOME/impactlib/numba`` (default ``~/.cache/impactlib/numba``; on Windows
``%LOCALAPPDATA%\\impactlib\\numba``, on macOS ``~/Library/Caches/impactlib/numba``).
A ``NUMBA_CACHE_DIR`` set by the user (or the Dockerfile) always wins.
"""
from __future__ import annotations

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


def configure() -> str | None:
    """Point Numba's cache at the user cache directory for an installed package (before
    any kernel is compiled); return the directory chosen, None when left to Numba."""
    if os.environ.get("NUMBA_CACHE_DIR") or not installed():
        return None
    path = str(user_cache_dir())
    os.environ["NUMBA_CACHE_DIR"] = path
    config = sys.modules.get("numba.core.config")
    if config is not None:   # numba already imported: its config read the variable already
        config.CACHE_DIR = path
    return path


configure()
