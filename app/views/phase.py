"""View 2: phase trajectory (x, ẋ) with the wall at x = g."""
from __future__ import annotations

from bokeh.models import ColumnDataSource, Span

from ..compute import SceneData
from ._figure import CURVE_TOOLS, LINE, WALL, make_figure
from .base import View


class PhaseView(View):
    key = "phase"

    def __init__(self):
        self.source = ColumnDataSource({"x": [], "v": []})
        self.figure = make_figure("phase_figure", "Phase trajectory (x, ẋ)",
                                  "displacement x", "velocity ẋ", tools=CURVE_TOOLS)
        self.wall = Span(location=0.0, dimension="height", line_color=WALL,
                         line_dash="dashed", line_width=1.5, name="phase_wall")
        self.figure.add_layout(self.wall)
        self.figure.line("x", "v", source=self.source, line_color=LINE, line_width=1.0,
                         name="phase")

    def show_scene(self, scene: SceneData) -> None:
        tr = scene.trajectory
        self.source.data = {"x": tr["x"], "v": tr["v"]}
        self.wall.location = scene.run.params.g
