"""The boundary curves drawn over the regime map: period-doubling, saddle-node and
grazing curves (``app.boundaries``), one multi-line renderer per kind, coloured and
dashed by kind, with an HTML legend (and the computation's status) beside the map. A tap
on a curve starts the scene on that curve's orbit (``app.orbit_pick``); elsewhere the
map's own tap applies."""
from __future__ import annotations

import html

from bokeh.models import ColumnDataSource, MultiLine

from ..boundaries import KINDS, BoundarySet
from ..orbit_pick import pick_on_curve
from ._figure import add_glyph

RENDERERS = {"period-doubling": "boundary_pd", "saddle-node": "boundary_sn",
             "grazing": "boundary_grazing"}
STYLE = {"period-doubling": ("#d62728", "solid"), "saddle-node": ("#1f3f99", "dashed"),
         "grazing": ("#111111", "dotted")}


class BoundaryOverlay:
    """Three renderers on the regime map ``view``'s figure, empty until curves arrive;
    ``pick(**settings)`` is what a tap on a curve does."""

    def __init__(self, view, pick):
        self.view, self._pick = view, pick
        view.claims.append(self.claim)
        figure = view.figure
        self.sources = {k: ColumnDataSource({"xs": [], "ys": []}) for k in KINDS}
        for kind in KINDS:
            colour, dash = STYLE[kind]
            add_glyph(figure, MultiLine, self.sources[kind], xs="xs", ys="ys",
                      line_color=colour, line_dash=dash, line_width=2.5,
                      name=RENDERERS[kind], level="overlay")
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

    def claim(self, event) -> bool:
        """A tap on a drawn curve: the scene starts on its orbit there (True); False
        where no curve is within reach or no orbit is found (the map's tap applies)."""
        req = self.view.request
        if self.curves is None or req is None or event.x is None or event.y is None:
            return False
        vx, vy = req.values_x, req.values_y
        picked = pick_on_curve(self.curves.curves, event.x, event.y,
                               float(vx[-1] - vx[0]), float(vy[-1] - vy[0]))
        if picked is None:
            return False
        self._pick(**picked.settings)
        return True

    def clear(self, status: str = "") -> None:
        for source in self.sources.values():
            source.data = {"xs": [], "ys": []}
        self.status = status
        self.curves = None

    def show(self, curves: BoundarySet, where: str = "") -> None:
        """Draw ``curves``; ``where`` they are computed goes on the status line ("" when
        no cluster is set, as on the map's)."""
        for kind in KINDS:
            xs, ys = curves.lines(kind)
            self.sources[kind].data = {"xs": xs, "ys": ys}
        at = f" — {where}" if where else ""
        self.status = (curves.message if curves.complete
                       else f"computing… {curves.message}") + at
        self.curves = curves
