"""Research view: the regime map, the (m, n) class of each cell of a grid over two
parameters (``map_x`` × ``map_y``), drawn as an image row block by row block, with a
legend of the classes, a marker at the current point and a tap that moves there (unless
an overlay claims it: a tap on a boundary curve)."""
from __future__ import annotations

import html

import numpy as np
from bokeh.events import Tap
from bokeh.models import (ColumnDataSource, HoverTool, Image, LinearColorMapper, Range1d,
                          Scatter)

from ..research import PALETTE, MapRequest, MapRows
from ..settings import AXIS_LABELS, SWEEP_RANGES, SYMBOLS
from ._figure import Kit, add_glyph, make_figure
from .base import View

PENDING = "rgba(0, 0, 0, 0)"


def cell_value(x: float, values: np.ndarray) -> float:
    """A tapped coordinate kept in the grid's range, rounded to a tenth of a cell."""
    lo, hi = float(values[0]), float(values[-1])
    x = min(max(float(x), lo), hi)
    step = (hi - lo) / max(values.size - 1, 1)
    digits = max(0, 1 - int(np.floor(np.log10(step)))) if step > 0 else 6
    return min(max(round(x, digits), lo), hi)


def legend_html(items) -> str:
    """Colour swatch, label and share of cells of each class."""
    total = sum(n for _, _, n in items) or 1
    rows = "".join(
        f"<div><span style='display:inline-block;width:12px;height:12px;margin-right:6px;"
        f"border:1px solid #999;background:{c}'></span>{html.escape(label)} — "
        f"{_share(n, total)}</div>" for c, label, n in items)
    return f"<div class='ie-legend' style='font-size:12px'>{rows}</div>"


class RegimeMapView(View):
    key = "regime_map"

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource({"image": [np.full((1, 1), np.nan, np.float32)],
                                        "x": [0.0], "y": [0.0], "dw": [1.0], "dh": [1.0]})
        self.current = ColumnDataSource({"x": [], "y": []})
        self.request: MapRequest | None = None
        self.image = np.full((1, 1), np.nan, np.float32)
        self.impacts = self.period = np.zeros((1, 1), dtype=np.int64)   # classify's codes
        self.labels: tuple = ()           # label of each class index
        self.legend = legend_html([])
        self.rows_done = 0
        self._pick = None
        #: Overlays asked first about a tap: claim(event) -> True when they handled it.
        self.claims: list = []
        self._end = ""
        lo_x, hi_x = SWEEP_RANGES["omega"]
        lo_y, hi_y = SWEEP_RANGES["r"]
        self.figure = make_figure("regime_map_figure", "Regime map", AXIS_LABELS["omega"],
                                  AXIS_LABELS["r"], x_range=Range1d(lo_x, hi_x),
                                  y_range=Range1d(lo_y, hi_y), kit=kit)
        mapper = LinearColorMapper(palette=list(PALETTE), low=-0.5, high=len(PALETTE) - 0.5,
                                   nan_color=PENDING)
        add_glyph(self.figure, Image, self.source, image="image", x="x", y="y", dw="dw",
                  dh="dh", color_mapper=mapper, name="regime_map")
        add_glyph(self.figure, Scatter, self.current, x="x", y="y", marker="circle_cross",
                  size=14, fill_color="white", fill_alpha=0.6, line_color="black",
                  line_width=2, name="regime_map_current", level="overlay")
        self.hover = HoverTool(tooltips=[("ω", "$x{0.000}"), ("r", "$y{0.000}")])
        self.figure.add_tools(self.hover)
        self.figure.on_event(Tap, self._on_tap)

    def connect(self, pick) -> None:
        self._pick = pick

    def started(self, req: MapRequest) -> None:
        """A new map: empty image over the grid, axes of the two parameters."""
        self.request = req
        vx, vy = req.values_x, req.values_y
        dx, dy = (vx[-1] - vx[0]) / (vx.size - 1), (vy[-1] - vy[0]) / (vy.size - 1)
        self.image = np.full((vy.size, vx.size), np.nan, np.float32)
        self.impacts = np.zeros((vy.size, vx.size), dtype=np.int64)
        self.period = np.zeros((vy.size, vx.size), dtype=np.int64)
        self.labels = ()
        self.rows_done = 0
        self.legend = legend_html([])
        self.source.data = {"image": [self.image], "x": [vx[0] - dx / 2], "y": [vy[0] - dy / 2],
                            "dw": [vx[-1] - vx[0] + dx], "dh": [vy[-1] - vy[0] + dy]}
        self.figure.x_range.update(start=vx[0] - dx / 2, end=vx[-1] + dx / 2)
        self.figure.y_range.update(start=vy[0] - dy / 2, end=vy[-1] + dy / 2)
        self.figure.xaxis.axis_label = AXIS_LABELS[req.name_x]
        self.figure.yaxis.axis_label = AXIS_LABELS[req.name_y]
        self.hover.tooltips = [(SYMBOLS[req.name_x], "$x{0.000}"),
                               (SYMBOLS[req.name_y], "$y{0.000}")]
        self.figure.title.text = f"{self._title()} — computing"
        self._mark(req.run.params)

    def _title(self) -> str:
        req = self.request
        p, run = req.run.params, req.run
        fixed = ", ".join(f"{SYMBOLS[n]} = {getattr(p, n):g}" for n in SYMBOLS
                          if n not in (req.name_x, req.name_y))
        return (f"Regime map {SYMBOLS[req.name_x]} × {SYMBOLS[req.name_y]}, {req.n}×{req.n}: "
                f"{fixed}, window [{run.t_record:g}, {run.t_end:g}] s")

    def rows(self, block: MapRows) -> None:
        """Fill the rows of one block (the whole image goes out in one assignment)."""
        a = block.start
        self.image = self.image.copy()
        rows = slice(a, a + block.classes.shape[0])
        self.image[rows] = block.classes
        self.impacts[rows], self.period[rows] = block.impacts, block.period
        self.labels = block.labels
        self.rows_done = block.rows_done
        self.legend = legend_html(block.legend)
        self.source.data = {**self.source.data, "image": [self.image]}

    def finished(self, text: str) -> None:
        self._end = text
        self.figure.title.text = f"{self._title()} — {text}"

    def mark_stale(self, stale: bool) -> None:
        """Note in the title that the settings changed since this picture was made."""
        note = " (settings changed: compute again)" if stale else ""
        self.figure.title.text = f"{self._title()} — {self._end}{note}"

    def show_scene(self, scene) -> None:
        self._mark(scene.run.params)

    def _mark(self, params) -> None:
        if self.request is not None:
            req = self.request
            self.current.data = {"x": [getattr(params, req.name_x)],
                                 "y": [getattr(params, req.name_y)]}

    def _on_tap(self, event) -> None:
        """A tap sets both parameters to the tapped cell's values."""
        req = self.request
        if self._pick is None or req is None or event.x is None or event.y is None:
            return
        if any(claim(event) for claim in self.claims):
            return
        self._pick(**{req.name_x: cell_value(event.x, req.values_x),
                      req.name_y: cell_value(event.y, req.values_y)})


def _share(n: int, total: int) -> str:
    share = 100 * n / total
    return f"{share:.1f}%" if share >= 0.1 else f"{n} cell{'s' if n > 1 else ''}"
