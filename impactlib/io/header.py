"""CSV files that carry their settings: ``# name = value`` lines, one header row, rows.

    # m = 1.0
    # omega = 2.0
    # method = exact
    # version = 0.2.0
    t,phase,v
    250.1,0.63,-3.9
    ...

``pandas.read_csv(f, comment="#")`` and ``numpy.loadtxt(f, delimiter=",", comments="#",
skiprows=1)`` read the rows; :func:`read_header` reads the settings back (as text).
"""
from __future__ import annotations

import io
import os

import numpy as np

from .._version import __version__

#: numbers as Python's repr (the shortest text that reads back bit for bit), whole-number
#: columns as integers
EXACT = None


def text(value) -> str:
    """A setting as it appears after ``=``: strings as they are, None as nothing, numbers
    by ``repr`` (so they read back exactly)."""
    if isinstance(value, str):
        return value
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (np.floating, np.integer)):
        return repr(value.item())
    if isinstance(value, int):
        return repr(int(value))         # an IntEnum (RunStatus) by its number
    return repr(value)


def settings_lines(settings: dict) -> str:
    """``# name = value`` lines for ``settings``, then ``version`` (the package's, unless
    ``settings`` names one)."""
    values = {str(k): text(v) for k, v in settings.items()}
    values.setdefault("version", __version__)
    for name, value in values.items():
        if "\n" in name or "\n" in value or "=" in name:
            raise ValueError(f"setting {name!r} = {value!r} does not fit on one '# name = value' line")
    return "".join(f"# {n} = {v}\n" for n, v in values.items())


def read_header(text_or_file) -> dict:
    """The ``# name = value`` lines at the top of a CSV text (or open file, or path) as
    a dict of strings."""
    if hasattr(text_or_file, "read"):
        text_ = text_or_file.read()
    elif isinstance(text_or_file, os.PathLike) or (
            isinstance(text_or_file, str) and "\n" not in text_or_file
            and os.path.exists(text_or_file)):
        with open(text_or_file, encoding="utf-8") as f:
            text_ = f.read()
    else:
        text_ = text_or_file
    out = {}
    for line in text_.splitlines():
        if not line.startswith("#"):
            break
        name, _, value = line[1:].partition("=")
        out[name.strip()] = value.strip()
    return out


def write_csv(file, columns: dict, settings: dict | None = None, fmt: str = EXACT) -> None:
    """Write equally long ``columns`` (name -> numbers) to ``file`` (a path or a text
    file): the settings block (omitted when ``settings`` is None), a header row, rows."""
    names = list(columns)
    arrays = [_column(columns[n]) for n in names]
    lengths = {a.size for a in arrays}
    if len(lengths) > 1:
        raise ValueError("columns differ in length: "
                         + ", ".join(f"{n}={a.size}" for n, a in zip(names, arrays)))
    if hasattr(file, "write"):
        _write(file, names, arrays, settings, fmt)
    else:
        with open(file, "w", encoding="utf-8", newline="") as f:
            _write(f, names, arrays, settings, fmt)


def _column(values) -> np.ndarray:
    a = np.asarray(values).ravel()
    if a.dtype.kind == "b":
        return a.astype(np.int64)
    if a.dtype.kind in "iu":
        return a
    return a.astype(float)


def _write(f, names, arrays, settings, fmt):
    if settings is not None:
        f.write(settings_lines(settings))
    f.write(",".join(names) + "\n")
    if fmt is None:
        for row in zip(*(a.tolist() for a in arrays)):
            f.write(",".join(map(repr, row)) + "\n")
    elif arrays and arrays[0].size:
        np.savetxt(f, np.column_stack([a.astype(float) for a in arrays]), delimiter=",", fmt=fmt)


def read_csv(file) -> tuple[dict, dict]:
    """(settings, columns) of a file :func:`write_csv` wrote: the header block as strings
    and each column as a float array."""
    if hasattr(file, "read"):
        content = file.read()
    else:
        with open(file, encoding="utf-8") as f:
            content = f.read()
    settings = read_header(content)
    lines = [ln for ln in content.splitlines() if not ln.startswith("#")]
    names = lines[0].split(",") if lines else []
    rows = np.loadtxt(io.StringIO("\n".join(lines[1:])), delimiter=",", ndmin=2) \
        if len(lines) > 1 else np.zeros((0, len(names)))
    return settings, {n: rows[:, i] for i, n in enumerate(names)}
