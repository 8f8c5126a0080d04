"""View 2: phase trajectory (x, ẋ) with the wall at x = g; a tap starts the motion
there (sets x0, v0); the animation's cursor moves on it."""
from __future__ import annotations

from collections.abc import Callable

from bokeh.events import Tap
from bokeh.models import ColumnDataSource, HoverTool, Line, Scatter, Span

from ..compute import SceneData
from ._figure import CURVE_TOOLS, LINE, WALL, Kit, add_glyph, auto_range_over, make_figure
from .base import View


def tap_to_state(view: View, wall: Callable[[], float]):
    """A Tap handler that asks the session to start from the tapped (x, ẋ), to four
    significant digits; a tap on the far side of the wall starts on it (x0 = g)."""
    def on_tap(event) -> None:
        if event.x is None or event.y is None:
            return
        g = float(wall())
        x0 = max(float(f"{float(event.x):.4g}"), g)
        view.request(x0=x0, v0=float(f"{float(event.y):.4g}"))
    return on_tap


class PhaseView(View):
    key = "phase"
    note = ("Velocity against position over the recorded window. A vertical jump at the "
            "dashed wall is an impact. Tap anywhere to start the motion from that "
            "(x, ẋ).")

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource({"x": [], "v": []})
        self.cursor = ColumnDataSource({"x": [0.0], "v": [0.0]}, syncable=False)
        self.figure = fig = make_figure("phase_figure", "Phase trajectory (x, ẋ)",
                                        "displacement x", "velocity ẋ",
                                        tools=CURVE_TOOLS, kit=kit)
        self.wall = Span(location=0.0, dimension="height", line_color=WALL,
                         line_dash="dashed", line_width=1.5, name="phase_wall")
        fig.add_layout(self.wall)
        line = add_glyph(fig, Line, self.source, x="x", y="v", line_color=LINE,
                         line_width=1.0, name="phase")
        add_glyph(fig, Scatter, self.cursor, x="x", y="v", size=11, color="#2a9d8f",
                  line_color="white", name="phase_cursor", level="overlay")
        auto_range_over(fig, line)
        fig.add_tools(HoverTool(renderers=[line], tooltips=[
            ("x", "@x{0.0000}"), ("ẋ", "@v{0.0000}")]))
        fig.on_event(Tap, tap_to_state(self, lambda: self.wall.location))

    def show_scene(self, scene: SceneData) -> None:
        tr = scene.trajectory
        self.source.data = {"x": tr["x"], "v": tr["v"]}
        self.wall.location = scene.run.params.g
