"""View 3: impact map, impact phase τᵢ mod T against the velocity before impact."""
from __future__ import annotations

from bokeh.models import ColumnDataSource, HoverTool, Range1d, Scatter

from ..compute import SceneData
from ._figure import IMPACT, Kit, add_glyph, make_figure, padded, set_range
from .base import View


class ImpactMapView(View):
    key = "impact_map"
    note = ("One dot per impact: when in the forcing period it happens (phase) and how "
            "fast the mass hits. One dot: one impact per period; a cloud: chaos.")

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource({"phase": [], "v": [], "t": []})
        self.pinned = None        # the overlay's source, made on the first pin
        self.figure = make_figure("impact_map_figure", "Impact map",
                                  "impact phase τᵢ mod T (s)", "impact velocity ẋ(τᵢ−)",
                                  x_range=Range1d(0.0, 3.14159), y_range=Range1d(-1.0, 0.0),
                                  kit=kit)
        dots = add_glyph(self.figure, Scatter, self.source, x="phase", y="v", size=5,
                         color=IMPACT, alpha=0.8, name="impact_map")
        self.figure.add_tools(HoverTool(renderers=[dots], tooltips=[
            ("τᵢ", "@t{0.000} s"), ("phase", "@phase{0.0000} s"),
            ("impact velocity", "@v{0.0000}")]))

    def pin(self, on: bool) -> None:
        """Keep the points shown now as a faint overlay (False: drop it)."""
        if self.pinned is None:
            if not on:
                return
            self.pinned = ColumnDataSource({"phase": [], "v": []})
            r = add_glyph(self.figure, Scatter, self.pinned, x="phase", y="v", size=5,
                          color="#999999", alpha=0.35, name="impact_map_pinned")
            self.figure.renderers = [r] + [x for x in self.figure.renderers if x is not r]
        self.pinned.data = ({"phase": self.source.data["phase"], "v": self.source.data["v"]}
                            if on else {"phase": [], "v": []})

    def show_scene(self, scene: SceneData) -> None:
        imp = scene.impacts
        self.source.data = {"phase": imp["phase"], "v": imp["v"], "t": imp["t"]}
        T = scene.run.params.T
        # the axes hold the pinned points too (they stay in view after a jump)
        pinned = {"phase": (), "v": ()} if self.pinned is None else self.pinned.data
        set_range(self.figure.x_range, 0.0, max([T, *pinned["phase"]]))
        set_range(self.figure.y_range, *padded(imp["v"], include=(0.0, *pinned["v"])))
        self.figure.title.text = f"Impact map, T = {T:.4g} s"
