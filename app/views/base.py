"""What every view is: a Bokeh figure and its data, fed by the session's results.

A view overrides the hooks of the results it shows; the session calls every hook of
every view in ``app.views.VIEWS`` and never needs to know which view shows what.
"""
from __future__ import annotations


class View:
    #: Attribute of the session that holds this view (``session.displacement``).
    key = ""
    #: Full page width below the diagram's progress row (else one cell of the grid).
    wide = False

    figure = None

    def link(self, views: dict) -> None:
        """Once every view of the page exists (``views`` by key): share a range with, or
        draw into, another view's figure."""

    def show_scene(self, scene) -> None:
        """A new trajectory (``app.compute.SceneData``: run, trajectory, impacts)."""

    def show_section(self, run, section: dict) -> None:
        """A new Poincaré section (columns t, x, v) of ``run``."""

    def diagram_started(self, run) -> None:
        """A new bifurcation diagram starts (nothing of it computed yet)."""

    def diagram_chunk(self, part: dict) -> None:
        """More of the diagram (columns omega, v, t, phase; ``drawn`` rows to plot)."""

    def show_branches(self, branches) -> None:
        """Periodic branches over the diagram's range (``app.branches.BranchSet``); a str
        says why there are none yet (computing, no diagram); None: switched off."""

    def diagram_finished(self, text: str) -> None:
        """The diagram ended: "complete", "partial (time limit)" or "failed"."""

    def connect(self, pick) -> None:
        """Gestures on the view may change settings through ``pick(**settings)``."""
