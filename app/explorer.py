"""The session controller: settings -> jobs -> views.

A settings change is validated into a ``Run``; what it changes decides the work:

- the trajectory (``Run.scene_key``) or psi: the scene job (scene views, badge, marker;
  a psi change alone re-samples the Poincaré section only);
- ``Run.diagram_key``: the diagram job restarts; omega alone only moves its marker;
- ``stability.readout_key`` (physics, start, window): the stability readout job;
- ``orbit_x0``, ``orbit_v0`` (a tap on a branch or a boundary curve): the orbit job
  (``app.orbit_pick``: the orbit the scene starts on, for the caption); a change of the
  physics or of the diagram's start empties them;
- ``branches`` on, or a finished diagram while it is on: the branch job (seeded from the
  diagram's chunks; cancelled when the diagram restarts or the overlay is switched off);
  a complete set of boundary curves on the regime map: their crossings with the
  diagram's line seed it too (the two views show the same events).

Each job is an ``app.jobs.Job`` (latest request wins, work off the event loop, results
back on it); each view gets the results it shows through its hooks (app.views.base).
The diagram and its branch overlay (``app.session_diagram``), compare mode
(``app.compare_mode``) and research mode (``app.research_panel``) own their jobs; both
are built when their mode is first shown (``mode``, a display setting like presenter).
Bad settings show a message naming the fields and keep the last good scene; nothing
raises into Panel (no traceback in the server log).
"""
from __future__ import annotations

import logging
from urllib.parse import urlencode
from concurrent.futures import ThreadPoolExecutor

import panel as pn

from . import accuracy, boundaries, branches, captions, compute, orbit_pick, stability, state
from .compare_mode import CompareMode
from .controls import Controls
from .downloads import Downloads
from .jobs import Job, SessionLoop, session_doc
from .panel_fixes import release_links, repair_reconnect, restore_on_history
from .research_panel import ResearchPanel
from .session_diagram import SessionDiagram
from .settings import BY_NAME, QUERY_NAMES, SWEEP_RANGES, Settings
from .views import VIEWS
from .views._figure import Kit, fit_titles

log = logging.getLogger(__name__)

_SCENE_POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="impact-scene")
_ACCURACY_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-accuracy")
_STABILITY_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-stability")
_BRANCH_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-branches")
#: Threads that drive regime maps and basins (each drives the core's own pool): at most
#: this many sessions compute one at a time, the others wait their turn.
_RESEARCH_POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="impact-research")
#: How long a served session's build waits for its first scene (s): one from the shared
#: cache takes a few ms and then goes out with the page; a longer one follows it.
SCENE_GRACE = 0.05


class Explorer(pn.viewable.Viewer):
    """One session of the app. ``args`` are the URL query arguments; ``loop`` runs results
    on the thread that owns the page (``app.jobs.KernelLoop`` in a notebook, see
    ``app.notebook``); without it, a served session uses its own (``SessionLoop``) and
    one without a server runs every job at once in the caller's thread."""

    def __init__(self, args=None, *, loop=None, **params):
        super().__init__(**params)
        values, scene, errors = state.from_query(args or {})
        self.settings = Settings(**values)
        self.run = self.scene = self.section = None
        self._scene_key = scene           # the paper's scene loaded last (None: defaults)
        self._wanted = None               # the latest valid settings (may be computing)
        self._keep_message = True         # the link's message stays until a user change
        self._restoring = False           # falling back to defaults (not a user change)
        doc = self._doc = session_doc()
        dispatch = self._loop = loop if loop is not None else SessionLoop(doc)
        background = doc is not None or loop is not None     # jobs in the pools
        self._loaded = doc is None        # served: a diagram to compute starts once the page is up
        self.views = [cls(kit) for kit in [Kit()] for cls in VIEWS]
        for view in self.views:
            setattr(self, view.key, view)
            view.request = self.request
            view.request_window = self._request_window
            view.connect(self.pick)
        for view in self.views:
            view.link({v.key: v for v in self.views})
            if view.ready is not None and doc is not None:
                doc.js_on_event("document_ready", view.ready)
        if doc is not None:
            repair_reconnect(doc)
            fit_titles(doc)
        self.downloads = Downloads(self)
        rooms = {"compare": lambda: c.compare_room(
                     self.compare.open(self.settings.presenter).figures),
                 "research": lambda: self.research.room}
        self.controls = c = Controls(self.settings, self.views, on_scene=self.load_scene,
                                     on_accuracy=self._on_accuracy, downloads=self.downloads,
                                     on_reset=self.reset, rooms=rooms)
        self.widgets, self.badge, self.caption = c.widgets, c.badge, c.caption
        self.message_pane, self.diagram_status = c.message_pane, c.diagram_status
        pool = _SCENE_POOL if background else None
        self.scene_job = Job("scene", lambda run, t: compute.scene_and_section(run, self._shown), dispatch,
                             pool=pool, on_result=self._scene_done, show_stale=True)
        self.window_job = Job("window", lambda req, t: compute.window_columns(*req), dispatch,
                              pool=pool, on_result=self._window_done)
        self._curves = None               # (request, set) of the last complete boundary curves
        self.diagram = SessionDiagram(self.views, self.controls, dispatch,
                                      _BRANCH_POOL if background else None,
                                      curve_seeds=self._curve_seeds)
        self.accuracy_job = Job(
            "accuracy", lambda run, t: accuracy.to_html(accuracy.compare_methods(run)),
            dispatch, pool=_ACCURACY_POOL if background else None,
            on_result=self._accuracy_done)
        self.orbit = None                 # (recognise_key, OrbitStart or None) of the last run
        self.orbit_job = Job("orbit", lambda run, t: orbit_pick.recognise(run), dispatch,
                             pool=pool, on_result=self._orbit_done)
        self.readout = None               # the stability readout shown (stability.Readout)
        self.stability_job = Job("stability", lambda run, t: stability.readout(run), dispatch,
                                 pool=_STABILITY_POOL if background else None,
                                 on_result=self._stability_done)
        # one heavy job per session: the regime map or the basins, the newest request wins
        self.research = ResearchPanel(self.widgets, dispatch=dispatch,
                                      pool=_RESEARCH_POOL if background else None,
                                      current=lambda: (self._wanted, self.scene),
                                      pick=self.pick, downloads=self.downloads,
                                      on_curves=self._curves_done)
        self.compare = CompareMode(dispatch, pool)
        c.pin_toggle.param.watch(lambda e: self.pin(e.new), "value")
        self.settings.param.watch(self._on_settings, [n for n in QUERY_NAMES
                                                      if n not in state.DISPLAY_FIELDS])
        self.settings.param.watch(self._on_display, list(state.DISPLAY_FIELDS))
        self._apply()
        self._on_display()
        self.controls.show_scene(self._scene_key)
        if errors:
            self._message("Not applied from the link: " + "; ".join(errors))
        if doc is not None:
            pn.state.on_session_destroyed(self._on_session_destroyed)
            pn.state.onload(self._on_load)
            restore_on_history(doc)
            # a scene from the shared cache comes back in milliseconds: give it that long,
            # so that it goes out with the page (and any diagram from the cache with it)
            self.scene_job.sent.wait(SCENE_GRACE)
            dispatch.built()

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
        for job in (self.scene_job, self.window_job, self.accuracy_job, self.stability_job,
                    self.orbit_job, self.research.job, self.research.boundary_job):
            job.cancel()
        self.diagram.cancel()
        self.compare.cancel()
        self._loop.close()
        self.release_links()

    def release_links(self) -> None:
        release_links(self.controls.layout)

    # -- settings -> jobs ----------------------------------------------------------------

    def request(self, **values) -> None:
        """Settings asked for by a view (a tap on the phase plane: x0, v0)."""
        self.pick(**values)

    def pin(self, on: bool) -> None:
        """Keep the maps shown now as a faint overlay (or drop it)."""
        for view in self.views:
            if hasattr(view, "pin"):
                view.pin(on)

    def show_mode(self, mode: str) -> None:
        """Give the page's plot area to ``mode`` (explore, compare or research); compare
        and research are built the first time they are shown."""
        if mode == "research":
            self.research.open()
        self.controls.show_mode(mode)

    def _on_display(self, *events) -> None:
        """Presenter mode on or off (type sizes and line widths of every view), the mode
        shown."""
        presenter = self.settings.presenter
        with pn.io.hold(self._doc):
            if not events or any(e.name == "presenter" for e in events):
                for view in self.views:
                    view.present(presenter)
                self.compare.present(presenter)
                self.controls.present(presenter)
            self.show_mode(self.settings.mode)
            if events:
                self._write_url()

    def load_scene(self, key: str | None) -> None:
        """Load one of the paper's scenes (all settings in one batch; None: the paper's
        defaults). The link and the caption name it even when no number changes."""
        self._scene_key = key
        self.controls.show_scene(key)
        self.settings.param.update(**state.base_settings(key))
        self._show_caption()
        if self._wanted == self.run:    # no number changed: no scene result will write it
            self._write_url()

    def reset(self) -> None:
        """Back to the scene loaded last (or the paper's defaults)."""
        self.load_scene(self._scene_key)

    def pick(self, **values) -> None:
        """Settings chosen by a gesture on a view (a tap on the diagram, the map...),
        rounded as a typed value is, so the widgets show what is computed."""
        self.settings.param.update(**{
            n: state.rounded(BY_NAME[n], v) if isinstance(v, float) else v
            for n, v in values.items()})

    def _on_settings(self, *events) -> None:
        if not self._restoring:
            self._keep_message = False
        changed = {e.name for e in events}
        st = self.settings
        span = SWEEP_RANGES[st.bif_param]
        if (changed & state.LEAVES_ORBIT and not changed & state.ORBIT_FIELDS
                and st.orbit_x0 is not None):
            # the orbit the scene started on belongs to the settings left
            self.settings.param.update(orbit_x0=None, orbit_v0=None)
            return
        if ("bif_param" in changed and not changed & {"bif_min", "bif_max"}
                and (st.bif_min, st.bif_max) != span):
            # another parameter: its own default range (the nested update applies it)
            self.settings.param.update(bif_min=span[0], bif_max=span[1])
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
            self._show_applied(self._wanted, refused=True)
            return
        if self._show_applied(run):
            return                      # the nested update applied it
        if self._wanted is None or run.diagram_key() != self._wanted.diagram_key():
            self.diagram.restart(run, start=self._loaded)
        if self._wanted is None or (stability.readout_key(run)
                                    != stability.readout_key(self._wanted)):
            self.controls.show_stability(None)
            self.stability_job.submit(run)
        previous, self._wanted = self._wanted, run
        if orbit_pick.recognise_key(run) not in (None, orbit_pick.recognise_key(previous)):
            self.orbit_job.submit(run)
        if previous is None or run.branches != previous.branches:
            self.diagram.show_branches(run.branches)
        self.scene_job.submit(run)

    def _curves_done(self, request, curves) -> None:
        """A complete set of boundary curves on the map: the diagram's branches start
        from their crossings too, so the two views show the same events."""
        self._curves = (request, curves)
        self.diagram.curves_changed()

    def _curve_seeds(self, run) -> tuple:
        """Crossings of the last complete boundary curves with the diagram's line (the
        y value of ``run``), when the map's x is the diagram's parameter and the curves
        are of ``run``'s other settings; () otherwise."""
        if self._curves is None or run is None:
            return ()
        request, curves = self._curves
        if request.name_x != run.bif_param:
            return ()
        mine = boundaries.BoundaryRequest(run, request.name_x, request.name_y)
        if mine.key()[:-1] != request.key()[:-1]:       # all but the map the cells are of
            return ()
        return branches.curve_seeds(curves.curves, run.bif_param,
                                    getattr(run.params, request.name_y), run.bif_min,
                                    run.bif_max)

    def _on_load(self) -> None:
        """The page is up: results computed so far go out now, the diagram starts."""
        self._loop.ready()
        with pn.io.hold(self._doc):
            self._loaded = True
            self.diagram.start()
            self._write_url()

    def _request_window(self, run, start, end, pixels) -> None:
        """A view wants the time series of [start, end] of ``run`` (a zoom, a pan)."""
        self.window_job.submit((run, start, end, pixels))

    def _window_done(self, request, result) -> None:
        if isinstance(result, Exception):
            log.warning("window failed: %s: %s", type(result).__name__, result)
            return
        for view in self.views:
            view.show_window(request[0], result)

    def _on_accuracy(self) -> None:
        self.controls.show_accuracy(None)
        self.accuracy_job.submit(self.run)

    # -- results -> views (on the event loop) -----------------------------------------------

    def _show_applied(self, run, refused: bool = False) -> bool:
        """Put the values of ``run`` (the one applied) into the widgets where they show
        something else: a refused value, a rounded one, an empty range. Keeps the
        message; True if anything changed (the nested update then applies ``run``)."""
        if run is None:
            return False
        now = state.snapshot(self.settings)
        differ = {n: v for n, v in state.applied(run).items() if not state.holds(now[n], v)}
        if not differ:
            return False
        keep, self._keep_message = self._keep_message or refused, True
        self._restoring = True
        try:
            self.settings.param.update(**differ)
        finally:
            self._restoring = False
            self._keep_message = keep
        return True

    def _scene_done(self, run, result) -> None:
        if isinstance(result, Exception) and self.run is None:
            # Nothing on screen yet (a link the core refuses): the scene's or the defaults
            base = "the scene's" if self._scene_key else "the default"
            self._message(f"Not applied — {result}. Showing {base} settings.")
            self._restoring = True
            try:
                self.settings.param.update(**state.base_settings(self._scene_key))
            finally:
                self._restoring = False
        elif isinstance(result, Exception):
            self._message(f"Not applied — {result}. Showing the last valid settings.")
            self._show_applied(self.run, refused=True)
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
        self._show_caption()
        self._write_url()

    def _accuracy_done(self, run, result) -> None:
        if isinstance(result, Exception):
            result = f"accuracy failed: {type(result).__name__}: {result}"
        self.controls.show_accuracy(result)

    def _stability_done(self, run, result) -> None:
        if isinstance(result, Exception):     # never raise into Panel
            log.warning("stability readout failed: %s: %s", type(result).__name__, result)
            result = stability.Readout("failed", f"no readout: {type(result).__name__}")
        self.readout = result
        self.controls.show_stability(stability.to_html(result))

    def _orbit_done(self, run, result) -> None:
        if isinstance(result, Exception):     # never raise into Panel
            log.warning("orbit check failed: %s: %s", type(result).__name__, result)
            result = None
        self.orbit = (orbit_pick.recognise_key(run), result)
        self._show_caption()

    def _show_caption(self) -> None:
        run = self._wanted if self._wanted is not None else self.run
        if run is None:
            return
        key = orbit_pick.recognise_key(run)
        start = self.orbit[1] if self.orbit is not None and self.orbit[0] == key else None
        self.controls.show_caption(captions.caption(run, self._scene_key) if start is None
                                   else captions.orbit_caption(run, start))

    def _message(self, text: str) -> None:
        self.controls.show_message(text, keep=self._keep_message)

    def _write_url(self) -> None:
        loc = pn.state.location
        if loc is not None and self.run is not None and self._loaded:
            display = {n: getattr(self.settings, n) for n in state.DISPLAY_FIELDS}
            # the whole query, so that a display setting back at its default leaves it
            loc.search = "?" + urlencode(state.to_query(self.run, self._scene_key, display))
