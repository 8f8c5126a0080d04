"""View 1: displacement x(t) with the wall at g, the impacts marked and the sticking
intervals shaded; the animation's time cursor moves on it.

The line is sampled for the window on screen: each zoom or pan asks the session for
that window's samples (``app.compute.window_columns``: enough per period and per pixel,
exact impact corners); until they arrive it shows the scene's own samples."""
from __future__ import annotations

from bokeh.core.property.descriptors import UnsetValueError
from bokeh.events import RangesUpdate
from bokeh.models import (ColumnDataSource, HoverTool, Line, Range1d, Scatter, Span, VSpan,
                          VStrip)

from ..compute import SceneData, first_window
from ._figure import (IMPACT, LINE, STICK, TIME_SERIES_TOOLS, WALL, Kit, add_glyph,
                      auto_range_over, make_figure)
from .base import View

#: A scene started on a periodic orbit opens on its first periods (long enough to see
#: an unstable orbit followed, then left); other scenes open on compute.first_window.
ORBIT_PERIODS_SHOWN = 24


class DisplacementView(View):
    key = "displacement"
    note = ("The mass's position against time. Red dots: impacts on the wall (dashed "
            "line at g); yellow bands: the mass rests on the wall (sticking). Zoom out "
            "for the whole recorded window.")

    def __init__(self, kit: Kit):
        #: The scene's dense samples (t, x, v) with exact impact corners; the animation
        #: plays from this source in the browser.
        self.source = ColumnDataSource({"t": [], "x": [], "v": []})
        self.impacts = ColumnDataSource({"t": [], "x": [], "v": []})
        self.sticking = ColumnDataSource({"start": [], "end": []})
        # moved by the animation in the browser only: never sent back to the server
        self.cursor = ColumnDataSource({"t": [0.0], "x": [0.0]}, syncable=False)
        self.figure = fig = make_figure("displacement_figure", "Displacement x(τ)",
                                        "time τ (s)", "displacement x",
                                        x_range=Range1d(0.0, 1.0), tools=TIME_SERIES_TOOLS,
                                        kit=kit)
        add_glyph(fig, VStrip, self.sticking, x0="start", x1="end", fill_color=STICK,
                  fill_alpha=0.35, line_alpha=0, name="displacement_sticking",
                  level="underlay")
        self.wall = Span(location=0.0, dimension="width", line_color=WALL,
                         line_dash="dashed", line_width=1.5, name="displacement_wall")
        fig.add_layout(self.wall)
        line = add_glyph(fig, Line, self.source, x="t", y="x", line_color=LINE,
                         line_width=1.2, name="displacement")
        dots = add_glyph(fig, Scatter, self.impacts, x="t", y="x", size=4, color=IMPACT,
                         name="displacement_impacts")
        # on the overlay layer: a frame of the animation repaints the cursor, not x(t)
        add_glyph(fig, VSpan, self.cursor, x="t", line_color="#2a9d8f", line_width=2,
                  line_alpha=0.8, name="displacement_cursor", level="overlay")
        auto_range_over(fig, line, dots)
        fig.add_tools(HoverTool(renderers=[line], mode="vline", tooltips=[
            ("τ", "@t{0.000} s"), ("x", "@x{0.0000}"), ("ẋ", "@v{0.0000}")]))
        self.run = None
        self._asked = None
        fig.on_event(RangesUpdate, self._on_ranges)

    def _pixels(self) -> int:
        """Width of the plot area in the browser (before the first render: a guess)."""
        try:
            return int(self.figure.inner_width)
        except UnsetValueError:     # not rendered yet
            return 1000

    def _on_ranges(self, event) -> None:
        if self.run is None or event.x0 is None or event.x1 is None:
            return
        window = (self.run, event.x0, event.x1, self._pixels())
        if window != self._asked:
            self._ask(*window)

    def _ask(self, *window) -> None:
        self._asked = window
        self.request_window(*window)

    def show_window(self, run, columns: dict) -> None:
        if run is not self.run:
            return
        self.source.data = columns
        envelope = len(columns["v"]) > 0 and columns["v"][0] != columns["v"][0]
        self.figure.title.text = ("Displacement x(τ)"
                                  + (", envelope: zoom in" if envelope else ""))

    def show_scene(self, scene: SceneData) -> None:
        g = scene.run.params.g
        tr = scene.trajectory
        self.source.data = {"t": tr["t"], "x": tr["x"], "v": tr["v"]}
        t = scene.impacts["t"]
        self.impacts.data = {"t": t, "x": [g] * len(t), "v": scene.impacts["v"]}
        self.sticking.data = dict(scene.sticking)
        self.wall.location = g
        self.run = run = scene.run
        # the x axis opens on the last few periods (sampled by the scene's own run) or
        # on an orbit's first periods; reset/zoom out shows the whole window
        t_record = run.scene_start[2]
        if run.orbit_x0 is not None:
            start, end = t_record, min(run.t_end, t_record + ORBIT_PERIODS_SHOWN * run.params.T)
        else:
            start, end = first_window(run)
        self.figure.x_range.update(start=start, end=end, reset_start=start, reset_end=end)
        self.figure.title.text = "Displacement x(τ)"
        self.figure.xaxis.axis_label = (f"time τ (s); zoom out: {t_record:g}–"
                                        f"{run.t_end:g} s")
        self._ask(run, start, end, self._pixels())
