"""The boundary curves drawn over the regime map: period-doubling, saddle-node and
grazing curves (``app.boundaries``), one multi-line renderer per kind, coloured and
dashed by kind, with an HTML legend (and the computation's status) beside the map."""
from __future__ import annotations

import html

from bokeh.models import ColumnDataSource

from ..boundaries import KINDS, BoundarySet

RENDERERS = {"period-doubling": "boundary_pd", "saddle-node": "boundary_sn",
             "grazing": "boundary_grazing"}
STYLE = {"period-doubling": ("#d62728", "solid"), "saddle-node": ("#1f3f99", "dashed"),
         "grazing": ("#111111", "dotted")}


class BoundaryOverlay:
    """Three renderers on ``figure`` (the regime map's), empty until curves arrive."""

    def __init__(self, figure):
        self.sources = {k: ColumnDataSource({"xs": [], "ys": []}) for k in KINDS}
        for kind in KINDS:
            colour, dash = STYLE[kind]
            figure.multi_line("xs", "ys", source=self.sources[kind], line_color=colour,
                              line_dash=dash, line_width=2.5, name=RENDERERS[kind],
                              level="overlay")
        self.status = ""
        self.curves: BoundarySet | None = None      # what is drawn

    def legend(self) -> str:
        """The kinds' line styles and the status, as HTML beside the map (the map's own
        legend is HTML too, and a legend inside the figure would hide cells)."""
        css = {"solid": "solid", "dashed": "dashed", "dotted": "dotted"}
        rows = "".join(
            f"<div><span style='display:inline-block;width:28px;vertical-align:middle;"
            f"margin-right:6px;border-top:3px {css[STYLE[k][1]]} {STYLE[k][0]}'></span>"
            f"{html.escape(k)} — {self._count(k)}</div>" for k in KINDS)
        return (f"<div class='ie-legend' style='font-size:12px;margin-top:8px'>{rows}"
                f"<div>{html.escape(self.status)}</div></div>")

    def _count(self, kind: str) -> str:
        n = len(self.sources[kind].data["xs"])
        return f"{n} curve{'s' if n != 1 else ''}"

    def clear(self, status: str = "") -> None:
        for source in self.sources.values():
            source.data = {"xs": [], "ys": []}
        self.status = status
        self.curves = None

    def show(self, curves: BoundarySet) -> None:
        for kind in KINDS:
            xs, ys = curves.lines(kind)
            self.sources[kind].data = {"xs": xs, "ys": ys}
        self.status = curves.message if curves.complete else f"computing… {curves.message}"
        self.curves = curves
