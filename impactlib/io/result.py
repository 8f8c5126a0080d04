"""What every result of the core can do: print in a few lines, show as an HTML table in
a notebook, compare by its data, become a pandas DataFrame, and be written to CSV with its
settings; sweeps and grids also become an xarray Dataset.

The result classes inherit :class:`Result` (or :class:`SweepResult`) and keep only their
data; how each one is summarised and tabulated lives in :mod:`impactlib.io.tables`.
"""
from __future__ import annotations

import dataclasses
import html
import math

import numpy as np

from . import tables
from .header import EXACT, write_csv

#: at most this many characters per summary line (the whole repr stays under 1000)
LINE_MAX = 110


class Result:
    """Mixin of the frozen result dataclasses (declared with ``repr=False, eq=False``)."""

    __slots__ = ()
    #: fields that are not data (timings): left out of ``==``
    _not_data = ("elapsed",)
    __hash__ = None

    def _lines(self) -> tuple[str, list[tuple[str, str]]]:
        title, rows = tables.adapter(self).summary(self)
        return _clip(title), [(k, _clip(v, LINE_MAX - len(k) - 4)) for k, v in rows[:8]]

    def __repr__(self) -> str:
        title, rows = self._lines()
        return "\n".join([title] + [f"  {k}: {v}" for k, v in rows])

    def _repr_html_(self) -> str:
        title, rows = self._lines()
        body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                       f"<td style='text-align:left'>{html.escape(v)}</td></tr>" for k, v in rows)
        return (f"<table><caption style='text-align:left'><b>{html.escape(title)}</b>"
                f"</caption>{body}</table>")

    def __eq__(self, other) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(same(getattr(self, f.name), getattr(other, f.name))
                   for f in dataclasses.fields(self) if f.name not in self._not_data)

    def settings(self) -> dict:
        """The parameters and run settings this result was computed with (the CSV header
        and the xarray attributes), by their Python API names."""
        return tables.adapter(self).settings(self)

    def to_dataframe(self, table: str | None = None):
        """A tidy pandas DataFrame: one row per impact, point or cell (see the class's
        ``tables``; ``table`` picks another one), the parameters as columns."""
        import pandas as pd

        ad = tables.adapter(self)
        cols = dict(ad.frame(self, table))
        cols.update(ad.labels(self, table))
        n = len(next(iter(cols.values()))) if cols else 0
        for name, value in ad.constants(self).items():
            cols.setdefault(name, np.full(n, value) if not isinstance(value, str)
                            else np.full(n, value, dtype=object))
        return pd.DataFrame(cols)

    def to_csv(self, path, table: str | None = None, fmt: str = EXACT) -> None:
        """Write the table of :meth:`to_dataframe` (numeric columns; names of classes and
        attractors go into the header) to ``path`` with the ``# name = value`` block of
        :meth:`settings` at the top."""
        ad = tables.adapter(self)
        settings = dict(self.settings())
        settings.update(ad.header_extra(self, table))
        write_csv(path, ad.frame(self, table), settings, fmt=fmt)


class SweepResult(Result):
    """A result over a grid or a sweep: also :meth:`to_xarray`."""

    __slots__ = ()

    def to_xarray(self):
        """An ``xarray.Dataset`` with named dimensions and coordinates, the settings as
        attributes (netCDF-safe types: round-trips through ``to_netcdf``).  Needs the
        optional extra ``xarray``."""
        try:
            import xarray as xr
        except ImportError:
            raise ImportError("to_xarray needs xarray: pip install 'impact-explorer[xarray]'") \
                from None
        data_vars, coords = tables.adapter(self).dataset(self)
        attrs = {k: _attr(v) for k, v in self.settings().items()}
        return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _attr(value):
    # netCDF attributes: numbers and text only
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if value is None:
        return ""
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    return str(value)


def _clip(text: str, width: int = LINE_MAX) -> str:
    return text if len(text) <= width else text[:max(1, width - 1)] + "…"


def same(a, b) -> bool:
    """Data equality: arrays elementwise (NaN equal to NaN, shapes and kinds equal),
    dataclasses field by field, containers item by item."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape or a.dtype.kind != b.dtype.kind:
            return False
        if a.dtype.kind in "fc":
            return bool(np.array_equal(a, b, equal_nan=True))
        if a.dtype.kind == "O":
            return all(same(x, y) for x, y in zip(a.ravel(), b.ravel()))
        return bool(np.array_equal(a, b))
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return False
        if isinstance(a, Result):
            return a == b
        return all(same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return (isinstance(b, (tuple, list)) and len(a) == len(b)
                and all(same(x, y) for x, y in zip(a, b)))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False
