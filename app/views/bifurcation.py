"""View 5: the live bifurcation diagram, impact velocity against the swept parameter
(``bif_param``), with a marker at its current value (moving the marker never touches the
diagram's sources). Independent starts are drawn by the renderer ``bifurcation``; a
continuation up / down by ``bifurcation_up`` / ``bifurcation_down`` in two colours. A tap
sets the swept parameter to the tapped value, unless an overlay claims it (a tap on a
branch: ``claims``); hovering reads a point out."""
from __future__ import annotations

import math

import numpy as np
from bokeh.events import Tap
from bokeh.models import (ColumnDataSource, HoverTool, Legend, LegendItem, Range1d, Scatter,
                          Span)

from ..compute import last
from ..diagram import COLUMNS
from ..settings import AXIS_LABELS, SYMBOLS
from ..state import Run
from ._figure import DIAGRAM_TOOLS, IMPACT, WALL, Kit, add_glyph, make_figure
from .base import View

#: Impacts of the current scene drawn on the marker.
MARKER_IMPACTS = 200
UP, DOWN = "#1f5fa8", "#e08214"
SOURCES = {0: "source", 1: "up_source", -1: "down_source"}


def _empty() -> dict:
    return {"omega": np.zeros(0), "v": np.zeros(0)}


def tap_value(x: float, lo: float, hi: float, n: int) -> float:
    """The tapped value, kept in [lo, hi] and rounded to a tenth of the diagram's step
    (so the link stays short and the value lies within one step of the tap)."""
    x = min(max(float(x), lo), hi)
    step = (hi - lo) / max(n - 1, 1)
    digits = max(0, 1 - math.floor(math.log10(step))) if step > 0 else 6
    return min(max(round(x, digits), lo), hi)


class BifurcationView(View):
    key = "bifurcation"

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource(_empty())
        self.up_source = ColumnDataSource(_empty())
        self.down_source = ColumnDataSource(_empty())
        self.current = ColumnDataSource(_empty())
        self.parts: list[dict] = []
        self.run: Run | None = None
        self._current_v = np.zeros(0)
        self._pick = None
        #: Overlays asked first about a tap: claim(event) -> True when they handled it.
        self.claims: list = []
        self.title = "Bifurcation diagram"
        self.figure = make_figure("bifurcation_figure", "Bifurcation diagram",
                                  AXIS_LABELS["omega"], "impact velocity ẋ(τᵢ−)",
                                  x_range=Range1d(0.1, 5.0),
                                  tools=DIAGRAM_TOOLS, kit=kit)
        self._common = dict(x="omega", y="v", size=2, alpha=0.55)
        self.renderers = [add_glyph(self.figure, Scatter, self.source, color=WALL,
                                    name="bifurcation", **self._common)]
        self.legend = None
        self.hover = HoverTool(renderers=list(self.renderers),
                               tooltips=self._tooltips("omega"))
        self.figure.add_tools(self.hover)
        self.marker = Span(location=2.0, dimension="height", line_color=IMPACT,
                           line_width=2, line_alpha=0.7, name="bifurcation_marker",
                           level="overlay")
        self.figure.add_layout(self.marker)
        add_glyph(self.figure, Scatter, self.current, x="omega", y="v", size=5, color=IMPACT,
                  name="bifurcation_current", level="overlay")
        self.figure.on_event(Tap, self._on_tap)

    def _add_continuation(self) -> None:
        """The up and down renderers and their legend, made on the first continuation
        (about 13 Bokeh models a page that never sweeps up or down does without)."""
        if self.legend is not None:
            return
        up = add_glyph(self.figure, Scatter, self.up_source, color=UP, name="bifurcation_up",
                       **self._common)
        down = add_glyph(self.figure, Scatter, self.down_source, color=DOWN,
                         name="bifurcation_down", **self._common)
        self.renderers += [up, down]
        self.legend = Legend(items=[LegendItem(label="sweep up", renderers=[up]),
                                    LegendItem(label="sweep down", renderers=[down])],
                             location="top_right")
        self.figure.add_layout(self.legend)
        self.hover.renderers = list(self.renderers)

    @staticmethod
    def _tooltips(name: str) -> list:
        return [(SYMBOLS[name], "@omega{0.0000}"), ("impact velocity", "@v{0.0000}")]

    def connect(self, pick) -> None:
        self._pick = pick

    def diagram_started(self, run: Run) -> None:
        """A new diagram starts: clear the points, set the range, labels and title."""
        for attr in SOURCES.values():
            getattr(self, attr).data = _empty()
        self.parts = []
        self.run = run
        name = run.bif_param
        self.figure.x_range.update(start=run.bif_min, end=run.bif_max)
        self.figure.xaxis.axis_label = AXIS_LABELS[name]
        self.hover.tooltips = self._tooltips(name)
        if run.bif_sweep != "independent":
            self._add_continuation()
        if self.legend is not None:
            self.legend.visible = run.bif_sweep == "both"
        p = run.params
        fixed = ", ".join(f"{SYMBOLS[n]} = {getattr(p, n):g}" for n in SYMBOLS if n != name)
        mode = "" if run.bif_sweep == "independent" else f", sweep {run.bif_sweep}"
        self.title = (f"Bifurcation diagram in {SYMBOLS[name]}: {fixed}, window "
                      f"[{run.t_record:g}, {run.t_end:g}] s{mode}")
        self.figure.title.text = self.title + " — computing"
        self._place_marker(getattr(p, name))

    def diagram_chunk(self, part: dict) -> None:
        """Stream one chunk (only the new points travel to the browser)."""
        self.parts.append(part)
        shown = part["drawn"]
        omega, v, direction = part["omega"][shown], part["v"][shown], part["direction"][shown]
        for d, attr in SOURCES.items():
            rows = direction == d
            if rows.any():
                getattr(self, attr).stream({"omega": omega[rows], "v": v[rows]})

    def table(self) -> dict:
        """Every recorded impact so far (also those drawn as one dot), sorted by value,
        then direction (up first), then time (for the CSV)."""
        if not self.parts:
            return {c: np.zeros(0) for c in COLUMNS}
        cols = {c: np.concatenate([p[c] for p in self.parts]) for c in COLUMNS}
        order = np.lexsort((cols["t"], -cols["direction"], cols["omega"]))
        return {c: cols[c][order] for c in COLUMNS}

    def diagram_finished(self, text: str) -> None:
        self.figure.title.text = f"{self.title} — {text}"

    def show_scene(self, scene) -> None:
        """Move the marker and show the current scene's last impacts on it."""
        self._current_v = last(scene.impacts["v"], MARKER_IMPACTS)
        name = self.run.bif_param if self.run is not None else "omega"
        self._place_marker(getattr(scene.run.params, name))

    def _place_marker(self, value: float) -> None:
        self.marker.location = value
        self.current.data = {"omega": [value] * len(self._current_v), "v": self._current_v}

    def _on_tap(self, event) -> None:
        """A tap sets the swept parameter to the tapped value."""
        run = self.run
        if self._pick is None or run is None or event.x is None:
            return
        if any(claim(event) for claim in self.claims):
            return
        self._pick(**{run.bif_param: tap_value(event.x, run.bif_min, run.bif_max,
                                                run.bif_n)})
