"""Research view: basins of attraction on the section t = 0 for the current parameters,
which attractor each start (x0, v0) settles on, drawn row block by row block, with the
attractors' section points, a legend, a marker at the scene's start and a tap that
starts the scene there."""
from __future__ import annotations

import numpy as np
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, Image, LinearColorMapper, Range1d, Scatter, Span

from ..research import BASIN_COLOURS, UNDECIDED, BasinsRequest, attractor_text
from ._figure import WALL, Kit, add_glyph, make_figure
from .base import View
from .regime_map import PENDING, cell_value, legend_html

#: Image values: 0 undecided, 1 + attractor index (at most 64 attractors, colours cycled).
PALETTE = (UNDECIDED,) + tuple(BASIN_COLOURS[i % len(BASIN_COLOURS)] for i in range(64))


class BasinsView(View):
    key = "basins"

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource({"image": [np.full((1, 1), np.nan, np.float32)],
                                        "x": [0.0], "y": [0.0], "dw": [1.0], "dh": [1.0]})
        self.points = ColumnDataSource({"x": [], "v": []})
        self.start = ColumnDataSource({"x": [], "v": []})
        self.request: BasinsRequest | None = None
        self.image = np.full((1, 1), np.nan, np.float32)
        self.attractors: tuple = ()
        self.legend = legend_html([])
        self.rows_done = 0
        self.message = ""
        self._pick = None
        self._end = ""
        self.figure = make_figure("basins_figure", "Basins of attraction",
                                  "initial position x₀", "initial velocity v₀",
                                  x_range=Range1d(0.0, 1.0), y_range=Range1d(-1.0, 1.0),
                                  kit=kit)
        mapper = LinearColorMapper(palette=list(PALETTE), low=-0.5, high=len(PALETTE) - 0.5,
                                   nan_color=PENDING)
        add_glyph(self.figure, Image, self.source, image="image", x="x", y="y", dw="dw",
                  dh="dh", color_mapper=mapper, name="basins")
        self.wall = Span(location=0.0, dimension="height", line_color=WALL, line_width=2,
                         name="basins_wall")
        self.figure.add_layout(self.wall)
        add_glyph(self.figure, Scatter, self.points, x="x", y="v", size=5, color="black",
                  name="basins_attractors", level="overlay")
        add_glyph(self.figure, Scatter, self.start, x="x", y="v", marker="circle_cross",
                  size=14, fill_color="white", fill_alpha=0.6, line_color="black",
                  line_width=2, name="basins_start", level="overlay")
        self.figure.on_event(Tap, self._on_tap)

    def connect(self, pick) -> None:
        self._pick = pick

    @property
    def xs(self) -> np.ndarray:
        return np.linspace(*self.request.x_range, self.request.n)

    @property
    def vs(self) -> np.ndarray:
        return np.linspace(*self.request.v_range, self.request.n)

    def started(self, req: BasinsRequest) -> None:
        self.request = req
        (x0, x1), (v0, v1), n = req.x_range, req.v_range, req.n
        dx, dv = (x1 - x0) / (n - 1), (v1 - v0) / (n - 1)
        self.image = np.full((n, n), np.nan, np.float32)
        self.attractors, self.rows_done, self.message = (), 0, ""
        self.legend = legend_html([])
        self.source.data = {"image": [self.image], "x": [x0 - dx / 2], "y": [v0 - dv / 2],
                            "dw": [x1 - x0 + dx], "dh": [v1 - v0 + dv]}
        self.points.data = {"x": [], "v": []}
        self.figure.x_range.update(start=x0 - dx / 2, end=x1 + dx / 2)
        self.figure.y_range.update(start=v0 - dv / 2, end=v1 + dv / 2)
        self.wall.location = req.run.params.g
        self.figure.title.text = f"{self._title()} — computing"

    def _title(self) -> str:
        p = self.request.run.params
        n = self.request.n
        return (f"Basins at phase 0, {n}×{n} starts: ω = {p.omega:g}, r = {p.r:g}, "
                f"c = {p.c:g}, g = {p.g:g}, m = {p.m:g}, k = {p.k:g}")

    def rows(self, block) -> None:
        """One ``il.BasinRows`` block: its rows, and the attractors found so far."""
        a = block.start
        self.image = self.image.copy()
        self.image[a:a + block.labels.shape[0]] = block.labels + 1
        self.rows_done = block.rows_done
        self.message = block.message
        if len(block.attractors) != len(self.attractors):
            self.attractors = block.attractors
            pts = [att.points for att in self.attractors if att.kind != "chaotic"]
            pts += [att.points[:200] for att in self.attractors if att.kind == "chaotic"]
            pts = np.concatenate(pts) if pts else np.zeros((0, 2))
            self.points.data = {"x": pts[:, 0], "v": pts[:, 1]}
        done = self.image[~np.isnan(self.image)].astype(np.int64)
        counts = np.bincount(done, minlength=len(self.attractors) + 1)
        items = [(PALETTE[1 + i], attractor_text(att), int(counts[1 + i]))
                 for i, att in enumerate(self.attractors)]
        if counts[0]:
            items.append((UNDECIDED, "undecided", int(counts[0])))
        self.legend = legend_html(sorted(items, key=lambda item: -item[2]))
        self.source.data = {**self.source.data, "image": [self.image]}

    def finished(self, text: str) -> None:
        self._end = text
        self.figure.title.text = f"{self._title()} — {text}"

    def mark_stale(self, stale: bool) -> None:
        """Note in the title that the settings changed since this picture was made."""
        note = " (settings changed: compute again)" if stale else ""
        self.figure.title.text = f"{self._title()} — {self._end}{note}"

    def show_scene(self, scene) -> None:
        run = scene.run
        x0 = run.x0 if run.x0 is not None else max(0.0, run.params.g)
        self.start.data = {"x": [x0], "v": [run.v0]}

    def _on_tap(self, event) -> None:
        """A tap starts the scene at the tapped (x0, v0)."""
        if self._pick is None or self.request is None or event.x is None or event.y is None:
            return
        self._pick(x0=cell_value(event.x, self.xs), v0=cell_value(event.y, self.vs))
