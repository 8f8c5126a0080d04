"""CSV downloads of what a session shows: impacts, Poincaré points, bifurcation diagram."""
from __future__ import annotations

import io

import numpy as np
import panel as pn


def to_csv(columns: dict) -> io.StringIO:
    """A CSV file (header line, then one row per sample) of equally long columns."""
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names]) \
        if names and len(columns[names[0]]) else np.zeros((0, len(names)))
    buf = io.StringIO()
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
                       "v_after": imp["v_after"]})

    def poincare_csv(self) -> io.StringIO:
        self._name(1, "poincare")
        s = self.session.section
        return to_csv({"t": s["t"], "x": s["x"], "v": s["v"]})

    def bifurcation_csv(self) -> io.StringIO:
        self._name(2, "bifurcation")
        view = self.session.bifurcation
        table = view.table()
        run = view.run
        # the value column is named after the swept parameter; direction only when
        # the sweep has one (+1 up, -1 down)
        cols = {run.bif_param if run is not None else "omega": table["omega"]}
        cols.update((c, table[c]) for c in ("v", "t", "phase"))
        if run is not None and run.bif_sweep != "independent":
            cols["direction"] = table["direction"]
        return to_csv(cols)
