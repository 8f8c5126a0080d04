"""View 1: displacement x(t) with the wall at g and the impacts marked."""
from __future__ import annotations

from bokeh.models import ColumnDataSource, Span

from ..compute import SceneData
from ._figure import IMPACT, LINE, WALL, make_figure


class DisplacementView:
    def __init__(self):
        self.source = ColumnDataSource({"t": [], "x": []})
        self.impacts = ColumnDataSource({"t": [], "x": []})
        self.figure = make_figure("displacement_figure", "Displacement x(τ)",
                                  "time τ (s)", "displacement x")
        self.wall = Span(location=0.0, dimension="width", line_color=WALL,
                         line_dash="dashed", line_width=1.5, name="displacement_wall")
        self.figure.add_layout(self.wall)
        self.figure.line("t", "x", source=self.source, line_color=LINE, line_width=1.2,
                         name="displacement")
        self.figure.scatter("t", "x", source=self.impacts, size=4, color=IMPACT,
                            name="displacement_impacts", legend_label="impacts")
        self.figure.legend.location = "top_right"
        self.figure.legend.label_text_font_size = "11px"
        self.figure.legend.background_fill_alpha = 0.6

    def update(self, scene: SceneData) -> None:
        g = scene.run.params.g
        tr = scene.trajectory
        self.source.data = {"t": tr["t"], "x": tr["x"]}
        t = scene.impacts["t"]
        self.impacts.data = {"t": t, "x": [g] * len(t)}
        self.wall.location = g
        self.figure.title.text = (f"Displacement x(τ), τ in [{scene.run.t_record:g}, "
                                  f"{scene.run.t_end:g}] s — wall at g = {g:g}")
