"""View 4: Poincaré map, (x, ẋ) sampled at τ = ψ + nT; a tap starts the motion there."""
from __future__ import annotations

from bokeh.events import Tap
from bokeh.models import ColumnDataSource, HoverTool, Range1d, Scatter

from ..state import Run
from ._figure import LINE, Kit, add_glyph, make_figure, padded, set_range
from .base import View
from .phase import tap_to_state


class PoincareView(View):
    key = "poincare"
    note = ("The state (x, ẋ) once per forcing period, at the same phase ψ. One point: "
            "period-1 motion; n points: period-n; a fractal cloud: chaos. Tap to start "
            "from a point.")

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource({"x": [], "v": [], "t": []})
        self.pinned = None        # the overlay's source, made on the first pin
        self.figure = make_figure("poincare_figure", "Poincaré map", "displacement x",
                                  "velocity ẋ", x_range=Range1d(-1.0, 1.0),
                                  y_range=Range1d(-1.0, 1.0), kit=kit)
        dots = add_glyph(self.figure, Scatter, self.source, x="x", y="v", size=5,
                         color=LINE, alpha=0.8, name="poincare")
        self.figure.add_tools(HoverTool(renderers=[dots], tooltips=[
            ("τ", "@t{0.000} s"), ("x", "@x{0.0000}"), ("ẋ", "@v{0.0000}")]))
        self._g = 0.0
        self.figure.on_event(Tap, tap_to_state(self, lambda: self._g))

    def pin(self, on: bool) -> None:
        """Keep the points shown now as a faint overlay (False: drop it)."""
        if self.pinned is None:
            if not on:
                return
            self.pinned = ColumnDataSource({"x": [], "v": []})
            r = add_glyph(self.figure, Scatter, self.pinned, x="x", y="v", size=5,
                          color="#999999", alpha=0.35, name="poincare_pinned")
            self.figure.renderers = [r] + [x for x in self.figure.renderers if x is not r]
        self.pinned.data = ({"x": self.source.data["x"], "v": self.source.data["v"]}
                            if on else {"x": [], "v": []})

    def _pinned(self, col: str):
        return () if self.pinned is None else self.pinned.data[col]

    def show_section(self, run: Run, section: dict) -> None:
        self._g = run.params.g
        self.source.data = {"x": section["x"], "v": section["v"], "t": section["t"]}
        # the axes hold the pinned points too (they stay in view after a jump)
        set_range(self.figure.x_range, *padded(section["x"], include=self._pinned("x")))
        set_range(self.figure.y_range, *padded(section["v"], include=self._pinned("v")))
        self.figure.title.text = f"Poincaré map, ψ = {run.psi_frac:.3g} T"
