"""View 1: displacement x(t) with the wall at g and the impacts marked."""
from __future__ import annotations

from bokeh.models import ColumnDataSource, Range1d, Span

from ..compute import SceneData
from ._figure import IMPACT, LINE, TIME_SERIES_TOOLS, WALL, make_figure
from .base import View

#: The x axis opens on the last few periods; reset/zoom out shows the whole window.
PERIODS_SHOWN = 8


class DisplacementView(View):
    key = "displacement"

    def __init__(self):
        self.source = ColumnDataSource({"t": [], "x": []})
        self.impacts = ColumnDataSource({"t": [], "x": []})
        self.figure = make_figure("displacement_figure", "Displacement x(τ)",
                                  "time τ (s)", "displacement x",
                                  x_range=Range1d(0.0, 1.0), tools=TIME_SERIES_TOOLS)
        self.wall = Span(location=0.0, dimension="width", line_color=WALL,
                         line_dash="dashed", line_width=1.5, name="displacement_wall")
        self.figure.add_layout(self.wall)
        self.figure.line("t", "x", source=self.source, line_color=LINE, line_width=1.2,
                         name="displacement")
        self.figure.scatter("t", "x", source=self.impacts, size=4, color=IMPACT,
                            name="displacement_impacts")

    def show_scene(self, scene: SceneData) -> None:
        g = scene.run.params.g
        tr = scene.trajectory
        self.source.data = {"t": tr["t"], "x": tr["x"]}
        t = scene.impacts["t"]
        self.impacts.data = {"t": t, "x": [g] * len(t)}
        self.wall.location = g
        run = scene.run
        start = max(run.t_record, run.t_end - PERIODS_SHOWN * run.params.T)
        self.figure.x_range.update(start=start, end=run.t_end, reset_start=start,
                                   reset_end=run.t_end)
        self.figure.title.text = f"Displacement x(τ), impacts in red, wall at g = {g:g}"
        self.figure.xaxis.axis_label = (f"time τ (s) — last {PERIODS_SHOWN} periods shown; "
                                        f"zoom out for {run.t_record:g}–{run.t_end:g} s")
