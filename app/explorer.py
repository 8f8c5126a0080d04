"""The session controller: settings -> jobs -> views.

A settings change is validated into a ``Run``; what it changes decides the work:

- the trajectory (``Run.scene_key``) or psi: the scene job (scene views, badge, marker;
  a psi change alone re-samples the Poincaré section only);
- ``Run.diagram_key``: the diagram job restarts; omega alone only moves its marker.

Each job is an ``app.jobs.Job`` (latest request wins, work off the event loop, results
back on it); each view gets the results it shows through its hooks (app.views.base).
Bad settings show a message naming the fields and keep the last good scene; nothing
raises into Panel (no traceback in the server log).
"""
from __future__ import annotations

import logging
from concurrent.futures import ThreadPoolExecutor

import panel as pn

from . import accuracy, compute, diagram, research, state
from .controls import Controls
from .downloads import Downloads
from .jobs import Job, SessionLoop, session_doc
from .panel_fixes import release_links
from .research_panel import MAP, ResearchPanel
from .scenes import BY_KEY
from .settings import QUERY_NAMES, SYMBOLS, Settings
from .views import VIEWS
from .views._figure import share_helpers

log = logging.getLogger(__name__)

_SCENE_POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="impact-scene")
_ACCURACY_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-accuracy")
#: Threads that drive regime maps and basins (each drives the core's own pool): at most
#: this many sessions compute one at a time, the others wait their turn.
_RESEARCH_POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="impact-research")


class Explorer(pn.viewable.Viewer):
    """One session of the app. ``args`` are the URL query arguments."""

    def __init__(self, args=None, **params):
        super().__init__(**params)
        values, errors = state.initial_settings(args or {})
        self.settings = Settings(**values)
        self.run = self.scene = self.section = None
        self._scene_run = None            # run as loaded by the last scene button
        self._wanted = None               # the latest valid settings (may be computing)
        self._keep_message = True         # the link's message stays until a user change
        self._restoring = False           # falling back to defaults (not a user change)
        doc = self._doc = session_doc()
        dispatch = self._loop = SessionLoop(doc)
        self._loaded = doc is None        # served: the diagram starts once the page is up
        self.views = [cls() for cls in VIEWS]
        for view in self.views:
            setattr(self, view.key, view)
            view.connect(self.pick)
        share_helpers([v.figure for v in self.views])
        self.downloads = Downloads(self)
        self.controls = c = Controls(self.settings, self.views, on_scene=self.load_scene,
                                     on_accuracy=self._on_accuracy, downloads=self.downloads)
        self.widgets, self.badge, self.caption = c.widgets, c.badge, c.caption
        self.message_pane, self.diagram_status = c.message_pane, c.diagram_status
        pool = None if doc is None else _SCENE_POOL
        self.scene_job = Job("scene", lambda run, t: compute.scene_and_section(run, self._shown), dispatch,
                             pool=pool, on_result=self._scene_done, show_stale=True)
        self.runner = Job("diagram", self._follow_diagram, dispatch)
        self.accuracy_job = Job(
            "accuracy", lambda run, t: accuracy.to_html(accuracy.compare_methods(run)),
            dispatch, pool=None if doc is None else _ACCURACY_POOL,
            on_result=self._accuracy_done)
        # one heavy job per session: the regime map or the basins, the newest request wins
        self.research_job = Job("research", self._research_work, dispatch,
                                pool=None if doc is None else _RESEARCH_POOL)
        self.research = ResearchPanel(self.widgets, compute=self.compute_research,
                                      cancel=self.cancel_research, pick=self.pick,
                                      downloads=self.downloads)
        self.controls.add_research(self.research.card)
        self.settings.param.watch(self._on_settings, list(QUERY_NAMES))
        self._apply()
        if errors:
            self._message("Some settings in the link were not valid and were replaced by "
                          "defaults: " + "; ".join(errors))
        if doc is not None:
            pn.state.on_session_destroyed(self._on_session_destroyed)
            pn.state.onload(self._on_load)

    def __panel__(self):
        return self.controls.layout

    @property
    def message(self) -> str:
        """The message shown about rejected input ('' if none)."""
        return self.controls.message

    def _shown(self):
        return self.run, self.scene, self.section

    def _on_session_destroyed(self, session_context) -> None:
        """The tab is gone: stop its jobs and let the whole session be collected."""
        for job in (self.scene_job, self.runner, self.accuracy_job, self.research_job):
            job.cancel()
        self._loop.close()
        self.release_links()

    def release_links(self) -> None:
        release_links(self.controls.layout)

    # -- settings -> jobs ----------------------------------------------------------------

    def load_scene(self, key: str) -> None:
        """Load one of the paper's scenes (all settings in one batch)."""
        sc = BY_KEY[key]
        self.settings.param.update(**sc.settings())
        self.controls.show_caption(sc.caption)
        self._scene_run = self._wanted
        self._mark_caption()

    def pick(self, **values) -> None:
        """Settings chosen by a gesture on a view (a tap on the diagram, the map...)."""
        self.settings.param.update(**values)

    def _on_settings(self, *events) -> None:
        if not self._restoring:
            self._keep_message = False
        changed = {e.name for e in events}
        st = self.settings
        if ("bif_param" in changed and not changed & {"bif_min", "bif_max"}
                and (st.bif_min, st.bif_max) != (None, None)):
            # another parameter: its own default range (the nested update applies it)
            self.settings.param.update(bif_min=None, bif_max=None)
            return
        try:
            with pn.io.hold(self._doc):   # one websocket message for all view updates
                self._apply()
        except Exception as exc:   # never raise into Panel: message, keep last scene
            log.warning("update failed: %s: %s", type(exc).__name__, exc)
            self._message(f"Could not update: {type(exc).__name__}: {exc}")

    def _apply(self) -> None:
        try:
            run = state.validate(state.snapshot(self.settings))
        except ValueError as exc:
            self._message(f"Not applied — {exc}. Showing the last valid settings.")
            return
        if self._wanted is None or run.diagram_key() != self._wanted.diagram_key():
            self._restart_diagram(run)
        self._wanted = run
        self.scene_job.submit(run)

    def _on_load(self) -> None:
        """The page is up: results computed so far go out now, the diagram starts."""
        self._loop.ready()
        with pn.io.hold(self._doc):
            self._loaded = True
            self._restart_diagram(self._wanted)
            self._write_url()

    def _restart_diagram(self, run) -> None:
        self._diagram_run, self._drawn, self._recorded = run, 0, 0
        for view in self.views:
            view.diagram_started(run)
        self.controls.show_diagram(f"computing {diagram.what(run)}…", 0)
        if self._loaded:
            self.runner.submit(run)

    def _follow_diagram(self, run, ticket) -> None:
        diagram.follow(run, ticket, self._on_chunk, self._on_done, self._on_diagram_error)

    def compute_research(self, kind: str) -> None:
        """Compute the regime map (``MAP``) or the basins (``BASINS``) of the current
        settings; supersedes the one under way."""
        run = self._wanted
        if run is None:
            return
        if not self.research.built:
            self.research.build()
        if kind == MAP:
            request = research.map_request(run)
        else:
            shown = self.scene.trajectory if self.scene is not None and \
                self.scene.run.params == run.params else None
            request = research.BasinsRequest(run, *research.basins_window(run, shown),
                                             run.basins_n)
        self.research.started(kind, request)
        self.research_job.submit((kind, request))

    def cancel_research(self) -> None:
        self.research_job.cancel()
        self.research.cancelled()

    def _research_work(self, job, ticket) -> None:
        """Stream the blocks of a regime map or basins picture to the research panel."""
        kind, request = job
        block = None
        try:
            blocks = (research.map_rows(request) if kind == MAP
                      else research.basins_rows(request))
            try:
                for block in blocks:
                    ticket.send(self.research.rows, kind, block)
                    if not ticket.live:       # before the next block is computed
                        break
            finally:
                blocks.close()
        except Exception as exc:     # a message on the view, one log line, no traceback
            log.warning("%s failed: %s: %s", kind, type(exc).__name__, exc)
            ticket.send(self.research.failed, kind, f"{type(exc).__name__}: {exc}")
        else:
            ticket.send(self.research.finished, kind, block)
        ticket.finish()

    def _on_accuracy(self) -> None:
        self.controls.show_accuracy(None)
        self.accuracy_job.submit(self.run)

    # -- results -> views (on the event loop) -----------------------------------------------

    def _scene_done(self, run, result) -> None:
        if isinstance(result, Exception) and self.run is None:
            # Nothing on screen yet (a link the core refuses): show the defaults.
            self._message(f"Not applied — {result}. Showing the default settings.")
            self._restoring = True
            try:
                self.settings.param.update(**state.defaults())
            finally:
                self._restoring = False
        elif isinstance(result, Exception):
            self._message(f"Not applied — {result}. Showing the last valid settings.")
        else:
            self._show(run, *result)

    def _show(self, run, scene, section) -> None:
        if not self._keep_message:
            self.controls.clear_message()
        if scene is not self.scene:
            for view in self.views:
                view.show_scene(scene)
            self.research.show_scene(scene)
            self.controls.show_badge(scene)
        if section is not self.section:
            for view in self.views:
                view.show_section(run, section)
        self.run, self.scene, self.section = run, scene, section
        self.research.show_settings(run)
        self._mark_caption()
        self._write_url()

    def _on_chunk(self, part: dict, done: int, total: int) -> None:
        self._drawn += len(part["drawn"])
        self._recorded += len(part["omega"])
        for view in self.views:
            view.diagram_chunk(part)
        self.controls.show_diagram(f"computing… {done}/{total} "
                                   f"{SYMBOLS[self._diagram_run.bif_param]} values", done, total)

    def _on_done(self, info: dict) -> None:
        text, end = diagram.status_text(self._diagram_run, info, self._recorded, self._drawn)
        self.controls.show_diagram(text, info["done"], info["total"])
        for view in self.views:
            view.diagram_finished(end)

    def _on_diagram_error(self, text: str) -> None:
        self.controls.show_diagram(f"diagram failed: {text}")
        for view in self.views:
            view.diagram_finished("failed")

    def _accuracy_done(self, run, result) -> None:
        if isinstance(result, Exception):
            result = f"accuracy failed: {type(result).__name__}: {result}"
        self.controls.show_accuracy(result)

    def _mark_caption(self) -> None:
        if self._scene_run is not None and self.run is not None:
            self.controls.mark_caption(self.run != self._scene_run)

    def _message(self, text: str) -> None:
        self.controls.show_message(text, keep=self._keep_message)

    def _write_url(self) -> None:
        loc = pn.state.location
        if loc is not None and self.run is not None and self._loaded:
            loc.update_query(**state.to_query(self.run))
