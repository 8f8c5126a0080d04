"""View 5: the live bifurcation diagram, impact velocity against ω, with a marker at the
current ω (moving the marker never touches the diagram's source)."""
from __future__ import annotations

import numpy as np
from bokeh.models import ColumnDataSource, Range1d, Span

from ..compute import last
from ..state import Run
from ._figure import IMPACT, POINTS_TOOLS, WALL, make_figure
from .base import View

COLUMNS = ("omega", "v", "t", "phase")
#: Impacts of the current scene drawn on the marker.
MARKER_IMPACTS = 200


def _empty() -> dict:
    return {"omega": np.zeros(0), "v": np.zeros(0)}


class BifurcationView(View):
    key = "bifurcation"
    wide = True

    def __init__(self):
        self.source = ColumnDataSource(_empty())
        self.current = ColumnDataSource(_empty())
        self.parts: list[dict] = []
        self.title = "Bifurcation diagram"
        self.figure = make_figure("bifurcation_figure", "Bifurcation diagram",
                                  "driving frequency ω (rad/s)", "impact velocity ẋ(τ_I−)",
                                  x_range=Range1d(0.1, 5.0), height=340,
                                  tools=POINTS_TOOLS + ",save")
        self.figure.scatter("omega", "v", source=self.source, size=2, color=WALL,
                            alpha=0.55, name="bifurcation")
        self.marker = Span(location=2.0, dimension="height", line_color=IMPACT,
                           line_width=2, line_alpha=0.7, name="bifurcation_marker",
                           level="overlay")
        self.figure.add_layout(self.marker)
        self.figure.scatter("omega", "v", source=self.current, size=5, color=IMPACT,
                            name="bifurcation_current", level="overlay")

    def diagram_started(self, run: Run) -> None:
        """A new diagram starts: clear the points, set the ω range and the title."""
        self.source.data = _empty()
        self.parts = []
        self.figure.x_range.update(start=run.bif_min, end=run.bif_max)
        p = run.params
        self.title = (f"Bifurcation diagram: r = {p.r:g}, c = {p.c:g}, g = {p.g:g}, "
                      f"m = {p.m:g}, k = {p.k:g}, window [{run.t_record:g}, {run.t_end:g}] s")
        self.figure.title.text = self.title + " — computing"

    def diagram_chunk(self, part: dict) -> None:
        """Stream one chunk (only the new points travel to the browser)."""
        self.parts.append(part)
        shown = part["drawn"]
        self.source.stream({"omega": part["omega"][shown], "v": part["v"][shown]})

    def table(self) -> dict:
        """Every recorded impact so far (also those drawn as one dot), sorted by ω then
        time (for the CSV)."""
        if not self.parts:
            return {c: np.zeros(0) for c in COLUMNS}
        cols = {c: np.concatenate([p[c] for p in self.parts]) for c in COLUMNS}
        order = np.lexsort((cols["t"], cols["omega"]))
        return {c: cols[c][order] for c in COLUMNS}

    def diagram_finished(self, text: str) -> None:
        self.figure.title.text = f"{self.title} — {text}"

    def show_scene(self, scene) -> None:
        """Move the ω marker and show the current scene's last impacts on it."""
        omega, v = scene.run.params.omega, last(scene.impacts["v"], MARKER_IMPACTS)
        self.marker.location = omega
        self.current.data = {"omega": [omega] * len(v), "v": v}
