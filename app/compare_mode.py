"""A session's compare mode: the view (``app.views.compare``) and the jobs that fill it.

Built when first opened. Its panels come from the shared caches: the Fig. 3 diagrams
from ``app.diagram``'s, the Fig. 7 sections from ``app.compute``'s, so a classroom
opening it at once computes each panel once.
"""
from __future__ import annotations

import logging

from . import compute, diagram, state
from .jobs import Job
from .scenes import BY_KEY
from .views.compare import DIAGRAMS, SECTIONS, CompareView

log = logging.getLogger(__name__)


class CompareMode:
    """``dispatch`` is the session's loop (``app.jobs.SessionLoop``), ``pool`` the
    executor the sections are computed in (None: in the caller's thread)."""

    def __init__(self, dispatch, pool):
        self._dispatch, self._pool = dispatch, pool
        self.view: CompareView | None = None
        self.jobs: list[Job] = []

    def open(self, presenter: bool) -> CompareView:
        """The view; the first call builds it and starts its ten panels."""
        if self.view is None:
            self.view = CompareView()
            self.view.present(presenter)
            runs = {k: state.validate({**state.defaults(), **BY_KEY[k].settings()})
                    for k in (*DIAGRAMS, *SECTIONS)}
            sections = Job("compare-sections",
                           lambda rs, t: {k: compute.section_columns(r) for k, r in rs.items()},
                           self._dispatch, pool=self._pool,
                           on_result=lambda rs, result: self._sections_done(result))
            self.jobs.append(sections)
            for key in DIAGRAMS:
                job = Job(f"compare-{key}", self._follower(key), self._dispatch)
                self.jobs.append(job)
                job.submit(runs[key])
            sections.submit({k: runs[k] for k in SECTIONS})
        return self.view

    def present(self, on: bool) -> None:
        if self.view is not None:
            self.view.present(on)

    def cancel(self) -> None:
        for job in self.jobs:
            job.cancel()

    def _follower(self, key: str):
        view = self.view

        def done(info):
            view.diagram_finished(key, "complete" if info["done"] >= info["total"]
                                  else "partial (time limit)")

        def work(run, ticket):
            view.diagram_started(key)
            diagram.follow(run, ticket, lambda part, d, n: view.diagram_chunk(key, part), done,
                           lambda text: view.diagram_finished(key, "failed"))
        return work

    def _sections_done(self, result) -> None:
        if isinstance(result, Exception):
            log.warning("compare sections failed: %s: %s", type(result).__name__, result)
            return
        self.view.show_sections(result)
