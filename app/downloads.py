"""CSV downloads of what a session shows: impacts, Poincaré points, bifurcation diagram.

Each file starts with ``# name = value`` lines: the settings it was computed with under
their URL names (m, c, k, g, r, omega, psi, t_end, t_record, method) and the
``version`` of impactlib, then one header row, then the rows. ``pandas.read_csv(f,
comment="#")`` or ``numpy.loadtxt(f, delimiter=",", skiprows=…)`` read it.
"""
from __future__ import annotations

import io
from importlib.metadata import PackageNotFoundError, version

import numpy as np
import panel as pn

from .state import to_query

#: Settings written at the top of every CSV file, by URL name.
HEADER_NAMES = ("m", "c", "k", "g", "r", "omega", "psi", "t_end", "t_record", "method")


def package_version() -> str:
    try:
        return version("impact-explorer")
    except PackageNotFoundError:
        return "unknown"


def header(run) -> str:
    """``# name = value`` lines of the settings of ``run`` (URL names and texts)."""
    q = to_query(run)
    lines = [f"# {n} = {q[n]}" for n in HEADER_NAMES if n in q]
    lines.append(f"# version = {package_version()}")
    return "\n".join(lines) + "\n"


def to_csv(columns: dict, run=None) -> io.StringIO:
    """A CSV file (the settings of ``run`` as comment lines, a header line, then one row
    per sample) of equally long columns."""
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names]) \
        if names and len(columns[names[0]]) else np.zeros((0, len(names)))
    buf = io.StringIO()
    if run is not None:
        buf.write(header(run))
    buf.write(",".join(names) + "\n")
    np.savetxt(buf, data, delimiter=",", fmt="%.10g")
    buf.seek(0)
    return buf


class Downloads:
    """The download buttons of one session; ``session`` has ``run``, ``scene``,
    ``section`` and the ``bifurcation`` view."""

    def __init__(self, session):
        self.session = session
        button = dict(color="default", sizing_mode="stretch_width")
        self.widgets = [
            pn.widgets.FileDownload(callback=self.impacts_csv, filename="impacts.csv",
                                    label="Impacts (CSV)", **button),
            pn.widgets.FileDownload(callback=self.poincare_csv, filename="poincare.csv",
                                    label="Poincaré points (CSV)", **button),
            pn.widgets.FileDownload(callback=self.bifurcation_csv, filename="bifurcation.csv",
                                    label="Bifurcation diagram (CSV)", **button),
        ]

    def _name(self, index: int, what: str) -> None:
        p = self.session.run.params
        self.widgets[index].filename = f"{what}_omega{p.omega:g}_r{p.r:g}_c{p.c:g}_g{p.g:g}.csv"

    def impacts_csv(self) -> io.StringIO:
        self._name(0, "impacts")
        imp = self.session.scene.impacts
        return to_csv({"t": imp["t"], "phase": imp["phase"], "v_before": imp["v"],
                       "v_after": imp["v_after"]}, self.session.run)

    def poincare_csv(self) -> io.StringIO:
        self._name(1, "poincare")
        s = self.session.section
        return to_csv({"t": s["t"], "x": s["x"], "v": s["v"]}, self.session.run)

    def bifurcation_csv(self) -> io.StringIO:
        self._name(2, "bifurcation")
        return to_csv(self.session.bifurcation.table(), self.session.run)
