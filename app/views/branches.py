"""The branch overlay on the bifurcation diagram: periodic branches continued over the
diagram's range (stable solid, unstable dashed) and their events as labelled markers.

It has no figure of its own: its renderers (``branches_stable``, ``branches_unstable``,
``branch_events``) are added to the diagram's figure the first time the overlay is
switched on, so a page without it carries none of their Bokeh models. Each orbit of m
impacts draws m curves, its impact velocities, in the diagram's coordinates. A tap on a
branch starts the scene on that orbit (``app.orbit_pick``); elsewhere the diagram's own
tap applies.
"""
from __future__ import annotations

import numpy as np
from bokeh.models import ColumnDataSource, LabelSet, MultiLine, Scatter, Title

from ..branches import SHORT
from ..orbit_pick import pick_on_branch
from ._figure import Kit, add_glyph
from .base import View

STABLE = "#1b7837"
UNSTABLE = "#c2185b"
EVENT = "#ffb000"
LEGEND = ("Branches: stable solid, unstable dashed; ◆ PD period doubling, SN saddle-node, "
          "NS Neimark–Sacker, graze grazing")


def branch_lines(branches) -> tuple[dict, dict]:
    """(stable, unstable) multi-line columns: each impact of each branch, cut where its
    stability changes (the pieces share their end point, so the curve is unbroken);
    inadmissible points (past a grazing, an impact velocity above 0: not a motion of the
    oscillator) are left out."""
    out = {True: {"xs": [], "ys": []}, False: {"xs": [], "ys": []}}
    for b in branches:
        ok = b.admissible & np.all(b.impact_velocities <= 0.0, axis=1)
        kind = np.where(ok, b.stable.astype(int), -1)
        cuts = np.flatnonzero(kind[1:] != kind[:-1]) + 1
        edges = [0, *cuts.tolist(), b.param.size]
        for a, c in zip(edges[:-1], edges[1:]):
            if kind[a] < 0:
                continue
            hi = c + 1 if c < b.param.size and kind[c] >= 0 else c
            if hi - a < 2:
                continue
            for j in range(b.impact_velocities.shape[1]):
                out[bool(kind[a])]["xs"].append(b.param[a:hi])
                out[bool(kind[a])]["ys"].append(b.impact_velocities[a:hi, j])
    return out[True], out[False]


def event_points(branches, x_span: float, y_span: float) -> dict:
    """One marker per impact velocity at each event. Labels (kind and value) only where
    they do not crowd an earlier label: at least 6 % of the x span or 12 % of the y span
    apart; every event keeps its marker (events past a grazing are not drawn)."""
    x, y, text, labelled, seen = [], [], [], [], set()
    for b in branches:
        for e in b.events:
            key = (e.kind, round(e.value, 4))
            if key in seen or np.any(b.impact_velocities[e.index] > 0.0):
                continue
            seen.add(key)
            for j, u in enumerate(b.impact_velocities[e.index]):
                u = float(u)
                free = j == 0 and all(abs(e.value - lx) > 0.06 * x_span
                                      or abs(u - ly) > 0.12 * y_span for lx, ly in labelled)
                if free:
                    labelled.append((e.value, u))
                x.append(e.value)
                y.append(u)
                text.append(f"{SHORT[e.kind]} {e.value:.3f}" if free else "")
    return {"x": x, "y": y, "text": text}


class BranchesView(View):
    key = "branches"

    def __init__(self, kit: Kit):
        self.target = None        # draws into the diagram's figure, with its kit
        self.stable = self.unstable = self.events = self.status = None
        self.renderers: list = []
        self.shown = None                 # the BranchSet drawn (None: none)
        self._pick = None

    def link(self, views: dict) -> None:
        self.target = views["bifurcation"].figure
        views["bifurcation"].claims.append(self.claim)

    def connect(self, pick) -> None:
        self._pick = pick

    def claim(self, event) -> bool:
        """A tap on a drawn branch: the scene starts on that orbit (True); False where no
        branch is within reach or no orbit is found there (the diagram's tap applies)."""
        if self.shown is None or self._pick is None or event.x is None or event.y is None:
            return False
        x_span = self.target.x_range.end - self.target.x_range.start
        ys = [u for b in self.shown.branches for u in b.impact_velocities.ravel()]
        y_span = max(max(ys) - min(ys), 1e-9) if ys else 1.0
        picked = pick_on_branch(self.shown.branches, event.x, event.y, x_span, y_span)
        if picked is None:
            return False
        self._pick(**picked.settings)
        return True

    def _build(self) -> None:
        self.stable = ColumnDataSource({"xs": [], "ys": []})
        self.unstable = ColumnDataSource({"xs": [], "ys": []})
        self.events = ColumnDataSource({"x": [], "y": [], "text": []})
        f = self.target
        labels = LabelSet(x="x", y="y", text="text", source=self.events, x_offset=5,
                          y_offset=3, text_font_size="11px", text_color="#333333",
                          background_fill_color="white", background_fill_alpha=0.75,
                          name="branch_event_labels")
        f.add_layout(labels)
        self.status = Title(text="", align="left", text_font_size="12px",
                            text_font_style="normal")
        f.add_layout(self.status, "below")
        self.renderers = [
            add_glyph(f, MultiLine, self.stable, xs="xs", ys="ys", line_color=STABLE,
                      line_width=2, name="branches_stable"),
            add_glyph(f, MultiLine, self.unstable, xs="xs", ys="ys", line_color=UNSTABLE,
                      line_width=1.5, line_dash="dashed", name="branches_unstable"),
            add_glyph(f, Scatter, self.events, x="x", y="y", marker="diamond", size=8,
                      fill_color=EVENT, line_color="#333333", name="branch_events"),
            labels, self.status]

    def show_branches(self, branches) -> None:
        if branches is None and not self.renderers:
            return
        if not self.renderers:
            self._build()
        for r in self.renderers:
            r.visible = branches is not None
        self.shown = None if branches is None or isinstance(branches, str) else branches
        if branches is None or isinstance(branches, str):
            self.stable.data = {"xs": [], "ys": []}
            self.unstable.data = {"xs": [], "ys": []}
            self.events.data = {"x": [], "y": [], "text": []}
            self.status.text = f"{LEGEND} — {branches}" if branches else ""
            return
        stable, unstable = branch_lines(branches.branches)
        self.stable.data, self.unstable.data = stable, unstable
        ys = [u for b in branches.branches for u in b.impact_velocities.ravel()]
        x_span = self.target.x_range.end - self.target.x_range.start
        y_span = (max(ys) - min(ys)) if ys else 1.0
        self.events.data = event_points(branches.branches, x_span, max(y_span, 1e-9))
        self.status.text = f"{LEGEND} — {branches.message}"
