"""What every view is: a Bokeh figure and its data, fed by the session's results.

A view overrides the hooks of the results it shows; the session calls every hook of
every view in ``app.views.VIEWS`` and never needs to know which view shows what.
"""
from __future__ import annotations

from collections.abc import Callable

from ._figure import style


class View:
    #: Attribute of the session that holds this view (``session.displacement``).
    key = ""
    #: Key of the view this one is drawn under, in that view's cell ("": a cell of its own).
    under = ""
    #: "What am I looking at": one or two sentences shown on request next to the view.
    note = ""

    figure = None
    #: A CustomJS to run once the page is ready (None: nothing to run).
    ready = None
    #: Asks the session to change settings (``request(x0=…, v0=…)``); set by the session.
    request: Callable[..., None] = staticmethod(lambda **settings: None)
    #: Asks the session for the time series of a window (``request_window(run, start,
    #: end, pixels)``); set by the session.
    request_window: Callable[..., None] = staticmethod(lambda run, start, end, pixels: None)

    @property
    def root(self):
        """The Bokeh model the page lays out (the figure, or the figure and its own
        controls)."""
        return self.figure

    def present(self, presenter: bool) -> None:
        """Large type and thick lines for a projector (True), or the screen (False)."""
        if self.figure is not None:         # a view may only draw into another's figure
            style(self.figure, presenter)

    def link(self, views: dict) -> None:
        """Once every view of the page exists (``views`` by key): share a range with, or
        draw into, another view's figure."""

    def show_scene(self, scene) -> None:
        """A new trajectory (``app.compute.SceneData``: run, trajectory, impacts)."""

    def show_window(self, run, columns: dict) -> None:
        """Samples (t, x, v) of the time window asked for with ``request_window``."""

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

    def diagram_classes(self, values, kinds) -> None:
        """What ``il.classify`` calls the motion at each of the diagram's ``values``
        (``app.motion_classes``); None: the sweep is not classified."""

    def connect(self, pick) -> None:
        """Gestures on the view may change settings through ``pick(**settings)``."""
