"""View 4: Poincaré map, (x, ẋ) sampled at τ = ψ + nT."""
from __future__ import annotations

from bokeh.models import ColumnDataSource, Range1d

from ..state import Run
from ._figure import LINE, make_figure, padded, set_range
from .base import View


class PoincareView(View):
    key = "poincare"

    def __init__(self):
        self.source = ColumnDataSource({"x": [], "v": []})
        self.figure = make_figure("poincare_figure", "Poincaré map", "displacement x",
                                  "velocity ẋ", x_range=Range1d(-1.0, 1.0),
                                  y_range=Range1d(-1.0, 1.0))
        self.figure.scatter("x", "v", source=self.source, size=5, color=LINE, alpha=0.8,
                            name="poincare")

    def show_section(self, run: Run, section: dict) -> None:
        self.source.data = {"x": section["x"], "v": section["v"]}
        set_range(self.figure.x_range, *padded(section["x"]))
        set_range(self.figure.y_range, *padded(section["v"]))
        self.figure.title.text = (f"Poincaré map at ψ = {run.psi_frac:.3g} T = "
                                  f"{run.psi:.4g} s — {len(section['x'])} points")
