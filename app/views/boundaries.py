"""The boundary curves drawn over the regime map: period-doubling, saddle-node and
grazing curves (``app.boundaries``), one multi-line renderer per kind, coloured and
dashed by kind, with a legend on the map's figure."""
from __future__ import annotations

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
                              legend_label=kind, level="overlay")
        figure.legend.location = "top_left"
        figure.legend.background_fill_alpha = 0.7
        figure.legend.label_text_font_size = "11px"
        self.status = ""
        self.curves: BoundarySet | None = None      # what is drawn

    def clear(self, status: str = "") -> None:
        for source in self.sources.values():
            source.data = {"xs": [], "ys": []}
        self.status = status
        self.curves = None

    def show(self, curves: BoundarySet) -> None:
        for kind in KINDS:
            xs, ys = curves.lines(kind)
            self.sources[kind].data = {"xs": xs, "ys": ys}
        self.status = curves.message
        self.curves = curves
