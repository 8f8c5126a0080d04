"""A session's bifurcation diagram: the streaming job, its status line, and the branch
overlay seeded from its chunks.

The diagram itself comes from ``app.diagram`` (shared between sessions: computed once,
replayed to the others); here its chunks go to the views as they arrive, the status
line counts them, and once the diagram ends the branch job (when the overlay is on)
continues the orbits it found. A restart cancels the branch job.
"""
from __future__ import annotations

import logging

import numpy as np

from . import branches, diagram, motion_classes
from .jobs import Job
from .settings import SYMBOLS

log = logging.getLogger(__name__)


class SessionDiagram:
    """``views`` get the diagram hooks (app.views.base), ``controls`` the status line;
    ``dispatch`` is the session's loop, ``branch_pool`` the executor of the branch job;
    ``curve_seeds(run)`` the crossings of the regime map's boundary curves with the
    diagram's line (``branches.curve_seeds``), seeds of the branches too."""

    def __init__(self, views, controls, dispatch, branch_pool, curve_seeds=lambda run: ()):
        self._views, self._controls = views, controls
        self._curve_seeds = curve_seeds
        self._seeded: tuple = ()          # the crossings the branch job was given
        self.job = Job("diagram", self._follow, dispatch)
        self.branch_job = Job("branches",
                              lambda req, t: branches.branches_for(req[0], req[1], t, req[2]),
                              dispatch, pool=branch_pool, on_result=self._branches_done)
        self.class_job = Job("classes",
                             lambda req, t: motion_classes.classify_values(
                                 req[0], req[1], lambda: t.live),
                             dispatch, pool=branch_pool, on_result=self._classes_done)
        self.run = None                   # the run the diagram is for
        self._started = False             # its job submitted
        self.parts: list[dict] = []       # its chunks so far (branch seeds)
        self.end = None                   # "complete", "partial (time limit)", "failed"
        self._branches = False            # the overlay is on

    def restart(self, run, start: bool) -> None:
        """A new diagram for ``run``: views cleared, status "computing"; the job starts
        when ``start`` (a served page starts it once the page is up, see ``start``), or
        at once when the diagram is complete in the shared cache (nothing to compute:
        a page being built gets it with its first pull)."""
        self.run, self.parts, self.end = run, [], None
        self._started = False
        self.class_job.cancel()
        if run.branches:
            self.branch_job.cancel()
            for view in self._views:
                view.show_branches("waiting for the diagram")
        for view in self._views:
            view.diagram_started(run)
        self._controls.show_diagram(f"computing {diagram.what(run)}…", 0)
        if start or diagram.CACHE.complete(run):
            self.start()

    def start(self) -> None:
        """Start the job for the diagram of the last restart, unless it is started."""
        if self.run is not None and not self._started:
            self._started = True
            self.job.submit(self.run)

    def show_branches(self, on: bool) -> None:
        """Branch overlay: off, waiting for the diagram, or computed from its chunks."""
        self._branches = on
        if not on:
            self.branch_job.cancel()
            for view in self._views:
                view.show_branches(None)
            return
        ready = self.end not in (None, "failed") and self.parts
        text = ("continuing the orbits the diagram found…" if ready else
                "waiting for the diagram" if self.end is None else
                "no diagram to start from")
        for view in self._views:
            view.show_branches(text)
        if ready:
            self._seeded = self._curve_seeds(self.run)
            self.branch_job.submit((self.run, diagram.merged(self.parts), self._seeded))

    def curves_changed(self) -> None:
        """New boundary curves on the map: branches from their crossings too, if the
        overlay is shown and they cross the line elsewhere than before."""
        if (self._branches and self.end not in (None, "failed") and self.parts
                and self._curve_seeds(self.run) != self._seeded):
            self.show_branches(True)

    def cancel(self) -> None:
        self.job.cancel()
        self.branch_job.cancel()
        self.class_job.cancel()

    # -- results (on the event loop) --------------------------------------------------------

    def _follow(self, run, ticket) -> None:
        diagram.follow(run, ticket, self._on_chunk, self._on_done, self._on_error)

    def _on_chunk(self, part: dict, done: int, total: int) -> None:
        self.parts.append(part)
        for view in self._views:
            view.diagram_chunk(part)
        self._controls.show_diagram(f"computing… {done}/{total} "
                                    f"{SYMBOLS[self.run.bif_param]} values", done, total)

    def _on_done(self, info: dict) -> None:
        recorded = sum(len(p["omega"]) for p in self.parts)
        drawn = sum(len(p["drawn"]) for p in self.parts)
        text, end = diagram.status_text(self.run, info, recorded, drawn)
        self._controls.show_diagram(text, info["done"], info["total"])
        self._ended(end)

    def _on_error(self, text: str) -> None:
        self._controls.show_diagram(f"diagram failed: {text}")
        self._ended("failed")

    def _ended(self, end: str) -> None:
        for view in self._views:
            view.diagram_finished(end)
        self.end = end
        if self._branches:
            self.show_branches(True)
        if end == "complete" and motion_classes.classifiable(self.run):
            values = np.unique(np.concatenate([p["values"] for p in self.parts]))
            self.class_job.submit((self.run, values))
        elif end == "complete":
            for view in self._views:
                view.diagram_classes(None, None)

    def _classes_done(self, request, result) -> None:
        if isinstance(result, Exception):     # never raise into Panel
            log.warning("classes failed: %s: %s", type(result).__name__, result)
            return
        if result is not None:
            for view in self._views:
                view.diagram_classes(request[1], result)

    def _branches_done(self, request, result) -> None:
        if isinstance(result, Exception):     # never raise into Panel
            log.warning("branches failed: %s: %s", type(result).__name__, result)
            result = f"failed: {type(result).__name__}: {result}"
        for view in self._views:
            view.show_branches(result)
