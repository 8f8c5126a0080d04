"""Compare mode: the paper's multi-panel figures as small multiples with shared, fixed
axes — Fig. 3 a–f (bifurcation diagrams, r = 0 … 0.9) and Fig. 7 a–d (Poincaré
sections of the chaotic motion at ω = 2.8, ψ = T/8 … 7T/8).

Not one of the page's views (``app.views.VIEWS``): the session builds it only when
compare mode is first opened, and feeds it from the shared caches (the diagrams from
``app.diagram``'s cache, the sections from ``app.compute``'s), so a classroom opening
it at once computes each panel once.
"""
from __future__ import annotations

import numpy as np
from bokeh.models import ColumnDataSource, Range1d, Scatter

from ..scenes import BY_KEY
from ._figure import LINE, WALL, Kit, add_glyph, make_figure, style

DIAGRAMS = tuple(f"fig3{c}" for c in "abcdef")
SECTIONS = tuple(f"fig7{c}" for c in "abcd")
#: Shared axes: the diagrams' ω range is the scenes' own; impact velocity and the
#: section's (x, ẋ) span what the paper's panels show (checked against the computed
#: panels in tests/app/test_explorer.py).
V_RANGE = (-5.6, 0.2)
SECTION_X, SECTION_V = (-0.05, 1.05), (-1.2, 1.6)


def _panel_title(key: str) -> str:
    """"Fig. 3(a), r = 0" / "Fig. 7(b), ψ = 3T/8" from the scene."""
    sc = BY_KEY[key]
    if key in SECTIONS:
        return f"Fig. 7({key[-1]}), ψ = {round(sc.changes['psi'] * 8)}T/8"
    return sc.caption.split("**")[1].split(":")[0].rstrip(".")


class CompareView:
    """Ten small figures: six diagrams and four sections, each set on shared ranges."""

    def __init__(self):
        kit = Kit()
        base = BY_KEY[DIAGRAMS[0]].settings()
        omega = Range1d(base["bif_min"], base["bif_max"])
        v = Range1d(*V_RANGE)
        self.diagrams = {}
        figs = []
        for key in DIAGRAMS:
            src = ColumnDataSource({"omega": [], "v": []})
            fig = make_figure(f"compare_{key}", _panel_title(key), "ω", "ẋ(τᵢ−)",
                              x_range=omega, y_range=v, tools="", kit=kit)
            add_glyph(fig, Scatter, src, x="omega", y="v", size=1.5, color=WALL, alpha=0.6)
            self.diagrams[key] = (src, fig)
            figs.append(fig)
        x, xv = Range1d(*SECTION_X), Range1d(*SECTION_V)
        self.sections = {}
        for key in SECTIONS:
            src = ColumnDataSource({"x": [], "v": []})
            fig = make_figure(f"compare_{key}", _panel_title(key), "x", "ẋ", x_range=x,
                              y_range=xv, tools="", kit=kit)
            add_glyph(fig, Scatter, src, x="x", y="v", size=2, color=LINE, alpha=0.7)
            self.sections[key] = (src, fig)
            figs.append(fig)
        for fig in figs:
            fig.toolbar_location = None
        self.figures = figs            # in page order; compare mode's room lays them out

    def present(self, presenter: bool) -> None:
        for fig in self.figures:
            style(fig, presenter)

    def diagram_started(self, key: str) -> None:
        self.diagrams[key][0].data = {"omega": [], "v": []}

    def diagram_chunk(self, key: str, part: dict) -> None:
        shown = part["drawn"]
        self.diagrams[key][0].stream({"omega": part["omega"][shown], "v": part["v"][shown]})

    def diagram_finished(self, key: str, text: str) -> None:
        fig = self.diagrams[key][1]
        if text != "complete":
            fig.title.text = f"{_panel_title(key)} — {text}"

    def show_sections(self, sections: dict) -> None:
        for key, sec in sections.items():
            self.sections[key][0].data = {"x": np.asarray(sec["x"]), "v": np.asarray(sec["v"])}
