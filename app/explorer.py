"""The Impact Explorer: one session's controls, views and wiring.

Settings -> validate -> Run. A change recomputes only what depends on it, decided by
comparing the new Run with the last good one:

- the trajectory key changed (omega, r, c, g, m, k, window, initial state, method):
  the four scene views, the motion badge and the bifurcation marker;
- psi (or the trajectory) changed: the Poincaré map only;
- the diagram key changed (r, c, g, m, k, window, initial state, diagram range):
  the diagram restarts; omega alone only moves its marker.

Bad settings show a message naming the fields and keep the last good scene; nothing
raises into Panel (no traceback in the server log).
"""
from __future__ import annotations

import io
import logging
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import panel as pn
import param
from panel.io.state import set_curdoc

from . import accuracy, compute, state
from . import diagram
from .diagram import DiagramRunner
from .scenes import SCENES
from .state import Run, Settings
from .views import BifurcationView, DisplacementView, ImpactMapView, PhaseView, PoincareView

log = logging.getLogger(__name__)

_ACCURACY_POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="impact-accuracy")
_SCENE_POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="impact-scene")

SIDEBAR_WIDTH = 310

CSS = """
.ie-badge {font-size: 16px;}
.ie-badge b {color: #1f5fa8;}
.ie-accuracy td, .ie-accuracy th {padding: 2px 6px; font-size: 12px; text-align: left;}
"""


class _PromptFloatSlider(pn.widgets.FloatSlider):
    # Panel waits 50 ms (Syncable._debounce) to coalesce browser events before running
    # callbacks; a scene update costs a few ms, so wait less and feel the slider follow.
    _debounce = 10


class EditableSlider(pn.widgets.EditableFloatSlider):
    """EditableFloatSlider whose slider reports moves after 10 ms instead of 50 ms."""

    _slider_widget = _PromptFloatSlider


def _csv(columns: dict) -> io.StringIO:
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names]) \
        if names and len(columns[names[0]]) else np.zeros((0, len(names)))
    buf = io.StringIO()
    buf.write(",".join(names) + "\n")
    np.savetxt(buf, data, delimiter=",", fmt="%.10g")
    buf.seek(0)
    return buf


def _session_doc():
    """The served session's Bokeh document, or None outside a server (tests)."""
    doc = pn.state.curdoc
    return doc if doc is not None and doc.session_context is not None else None


def _dispatcher(doc):
    """Run a function on the session's event loop (safe from any thread), holding the
    document so that all its model changes go out in one message."""
    if doc is None:
        return lambda fn: fn()

    def dispatch(fn):
        def held():
            with set_curdoc(doc), pn.io.hold(doc):
                fn()
        doc.add_next_tick_callback(held)
    return dispatch


class Explorer(pn.viewable.Viewer):
    """One session of the app. ``args`` are the URL query arguments."""

    message = param.String(default="", doc="Visible message about rejected input.")

    def __init__(self, args=None, **params):
        super().__init__(**params)
        values, errors = state.initial_settings(args or {})
        self.settings = Settings(**values)
        self.run: Run | None = None
        self.scene: compute.SceneData | None = None
        self.section: dict | None = None
        self._scene_run: Run | None = None   # run as loaded by the last scene button
        self._doc = _session_doc()
        self._dispatch = _dispatcher(self._doc)
        self.displacement = DisplacementView()
        self.phase = PhaseView()
        self.impact_map = ImpactMapView()
        self.poincare = PoincareView()
        self.bifurcation = BifurcationView()
        self.runner = DiagramRunner(self._dispatch, self._on_chunk, self._on_done,
                                    self._on_diagram_error)
        self.diagram_elapsed: float | None = None
        # Served: start the diagram once the page is connected (updates to Panel panes
        # made before that can be lost); without a server: at once.
        self._loaded = self._doc is None
        self._wanted: Run | None = None   # the latest valid settings (may be computing)
        self._busy = False                # a scene job of this session is in flight
        self._keep_message = True         # the link's message stays until a user change
        self._restoring = False           # falling back to defaults (not a user change)
        self._build_widgets()
        self.settings.param.watch(self._on_settings, list(state.QUERY_NAMES))
        self._apply()
        if errors:
            self._show_message("Some settings in the link were not valid and were "
                               "replaced by defaults: " + "; ".join(errors))
        self._layout = self._build_layout()
        if self._doc is not None:
            pn.state.on_session_destroyed(self._on_session_destroyed)
            pn.state.onload(self._on_load)

    def _on_session_destroyed(self, session_context) -> None:
        """The tab is gone: stop the diagram and let the whole session be collected."""
        self.runner.cancel()
        self.release_links()

    def release_links(self) -> None:
        """Drop this session's entries from Panel's class-wide link registry.

        Panel 1.9.4 keeps every jslink/jscallback in ``panel.links.Callback.registry``, a
        WeakKeyDictionary keyed by the source widget whose values refer back to that key
        (each EditableFloatSlider links its text input to its slider), so the entries of
        a closed session never go away and keep the whole session alive: widgets,
        Settings, figures and their data, a few MB per closed tab, for good.
        (tests/reliability/test_load.py checks that closed sessions are freed.)
        """
        from panel.links import Callback

        owned = {id(obj) for obj in self._layout.select()}
        for key in list(Callback.registry.keys()):
            if id(key) in owned:
                Callback.registry.pop(key, None)

    # -- widgets and layout ------------------------------------------------------------

    def _build_widgets(self) -> None:
        s = self.settings
        p = s.param

        def slider(name, fmt="0.000"):
            par = p[name]
            lo, hi = par.softbounds
            return EditableSlider.from_param(
                par, start=lo, end=hi, step=par.step, format=fmt,
                sizing_mode="stretch_width", label=par.label, css_classes=[f"ie-w-{name}"])

        def number(name, cls=pn.widgets.FloatInput, **kw):
            par = p[name]
            return cls.from_param(par, description=par.doc, label=par.label,
                                  sizing_mode="stretch_width", css_classes=[f"ie-w-{name}"],
                                  **kw)

        w = self.widgets = {
            "omega": slider("omega"), "r": slider("r"), "c": slider("c"),
            "g": slider("g"), "m": number("m"), "k": number("k"),
            "psi": slider("psi"),
            "t_end": number("t_end"), "t_record": number("t_record"),
            "x0": number("x0"), "v0": number("v0"),
            "method": pn.widgets.Select.from_param(p.method, label=p.method.label,
                                                   description=p.method.doc,
                                                   css_classes=["ie-w-method"],
                                                   sizing_mode="stretch_width"),
            "dt": number("dt", format="0.[000000]"),
            "rtol": number("rtol", format="0.[0000000000]"),
            "atol": number("atol", format="0.[000000000000]"),
            "bif_min": number("bif_min"), "bif_max": number("bif_max"),
            "bif_n": number("bif_n", cls=pn.widgets.IntInput),
        }
        self.message_pane = pn.pane.Alert("", alert_type="warning", visible=False,
                                          css_classes=["ie-message"],
                                          sizing_mode="stretch_width")
        self.badge = pn.pane.HTML("", css_classes=["ie-badge"], sizing_mode="stretch_width",
                                  stylesheets=[CSS])
        self.caption = pn.pane.Markdown(
            "Paper defaults: m = 1, c = 0.05, k = 1, g = 0, r = 0.8, ω = 2. "
            "Pick a scene of the paper or move a slider.",
            css_classes=["ie-caption"], sizing_mode="stretch_width")
        self.scene_buttons = []
        for sc in SCENES:
            b = pn.widgets.Button(label=sc.label, color="primary", variant="outline",
                                  margin=(2, 3),
                                  css_classes=[f"ie-scene-{sc.key}"],
                                  description=sc.caption.split("**")[1])
            b.on_click(lambda event, sc=sc: self.load_scene(sc.key))
            self.scene_buttons.append(b)
        self.progress = pn.indicators.Progress(value=0, max=100, width=200, height=14,
                                               bar_color="primary", margin=(8, 10))
        self.diagram_status = pn.pane.HTML("", css_classes=["ie-diagram-status"],
                                           sizing_mode="stretch_width")
        self.downloads = [
            pn.widgets.FileDownload(callback=self._impacts_csv, filename="impacts.csv",
                                    label="Impacts (CSV)", color="default",
                                    sizing_mode="stretch_width"),
            pn.widgets.FileDownload(callback=self._poincare_csv, filename="poincare.csv",
                                    label="Poincaré points (CSV)", color="default",
                                    sizing_mode="stretch_width"),
            pn.widgets.FileDownload(callback=self._bifurcation_csv,
                                    filename="bifurcation.csv",
                                    label="Bifurcation diagram (CSV)",
                                    color="default", sizing_mode="stretch_width"),
        ]
        self.accuracy_button = pn.widgets.Button(
            label="Compare methods", color="primary", sizing_mode="stretch_width",
            description="Run exact, rk4 and rk45 on the current scene and compare their "
                        "impacts and run times (not recomputed on slider moves).")
        self.accuracy_button.on_click(self._on_accuracy)
        self.accuracy_pane = pn.pane.HTML("", css_classes=["ie-accuracy-out"],
                                          stylesheets=[CSS], sizing_mode="stretch_width")

    def _with_tip(self, name):
        """Sliders have no tooltip of their own: an (i) icon with the setting's doc."""
        doc = self.settings.param[name].doc
        return pn.Row(self.widgets[name], pn.widgets.TooltipIcon(value=doc, margin=(22, 0, 0, 0)),
                      sizing_mode="stretch_width")

    def _build_layout(self):
        w = dict(self.widgets)
        for name in ("omega", "r", "c", "g", "psi"):
            w[name] = self._with_tip(name)
        group = pn.layout.Card
        sidebar = pn.Column(
            group(w["omega"], w["r"], w["c"], w["g"], pn.Row(w["m"], w["k"]),
                  title="Physics", collapsible=False, sizing_mode="stretch_width"),
            group(w["psi"], title="Poincaré section", collapsible=False,
                  sizing_mode="stretch_width"),
            group(pn.Row(w["t_end"], w["t_record"]), pn.Row(w["x0"], w["v0"]),
                  w["method"], w["dt"], pn.Row(w["rtol"], w["atol"]),
                  title="Time window, start, method", collapsed=True,
                  sizing_mode="stretch_width"),
            group(pn.Row(w["bif_min"], w["bif_max"]), w["bif_n"],
                  title="Bifurcation diagram range", collapsed=True,
                  sizing_mode="stretch_width"),
            group(*self.downloads, title="Downloads", collapsed=True,
                  sizing_mode="stretch_width"),
            group(self.accuracy_button, self.accuracy_pane, title="Accuracy",
                  collapsed=True, sizing_mode="stretch_width"),
            width=SIDEBAR_WIDTH,
        )
        pane = dict(sizing_mode="stretch_width")
        plots = pn.GridBox(
            pn.pane.Bokeh(self.displacement.figure, **pane),
            pn.pane.Bokeh(self.phase.figure, **pane),
            pn.pane.Bokeh(self.impact_map.figure, **pane),
            pn.pane.Bokeh(self.poincare.figure, **pane),
            ncols=2, sizing_mode="stretch_width")
        main = pn.Column(
            pn.pane.Markdown("## Impact Explorer — forced oscillator with a rigid endstop",
                             margin=(0, 10)),
            self.message_pane,
            pn.FlexBox(*self.scene_buttons, sizing_mode="stretch_width"),
            self.caption,
            self.badge,
            plots,
            pn.Row(self.progress, self.diagram_status, sizing_mode="stretch_width"),
            pn.pane.Bokeh(self.bifurcation.figure, **pane),
            sizing_mode="stretch_width",
        )
        return pn.Row(sidebar, main, sizing_mode="stretch_width")

    def __panel__(self):
        return self._layout

    # -- state changes -------------------------------------------------------------------

    def load_scene(self, key: str) -> None:
        """Load one of the paper's scenes (all settings in one batch)."""
        sc = next(s for s in SCENES if s.key == key)
        self.settings.param.update(**sc.settings())
        self.caption.object = sc.caption
        self._scene_run = self._wanted
        self._update_caption_note()

    def _on_settings(self, *events) -> None:
        if not self._restoring:
            self._keep_message = False
        try:
            with pn.io.hold(self._doc):   # one websocket message for all view updates
                self._apply()
        except Exception as exc:   # never raise into Panel: message, keep last scene
            log.warning("update failed: %s: %s", type(exc).__name__, exc)
            self._show_message(f"Could not update: {type(exc).__name__}: {exc}")

    def _apply(self) -> None:
        """Validate the settings; restart the diagram if its inputs changed; request the
        scene. Served, scenes are computed in a worker thread, one job per session at a
        time, latest settings first, so a slow scene never blocks the event loop."""
        try:
            run = state.validate(state.snapshot(self.settings))
        except ValueError as exc:
            self._show_message(f"Not applied — {exc}. Showing the last valid settings.")
            return
        if self._wanted is None or run.diagram_key() != self._wanted.diagram_key():
            self._restart_diagram(run)
        self._wanted = run
        if self._doc is None:
            self._scene_done(run, self._compute(run))
        elif not self._busy:
            self._busy = True
            _SCENE_POOL.submit(self._scene_work)

    def _compute(self, run: Run):
        """(scene, section) for ``run``, reusing what did not change since the shown
        run; or the exception that stopped it (ValueError: the core refused the
        settings). Never raises."""
        prev = self.run
        try:
            if prev is not None and run.scene_key() == prev.scene_key():
                scene = self.scene
            else:
                scene = compute.build_scene(run)
            if scene is self.scene and run.psi == prev.psi:
                section = self.section
            else:
                section = compute.section_columns(run)
        except ValueError as exc:
            return exc
        except Exception as exc:   # reported on the page, one line in the log
            log.warning("scene failed: %s: %s", type(exc).__name__, exc)
            return RuntimeError(f"{type(exc).__name__}: {exc}")
        return scene, section

    def _scene_work(self) -> None:
        """Worker thread: compute the latest wanted run, hand it to the event loop."""
        run = self._wanted
        result = self._compute(run)
        self._dispatch(lambda: self._scene_done(run, result))

    def _scene_done(self, run: Run, result) -> None:
        """Event loop: show the result; if the settings moved on meanwhile, go again."""
        if isinstance(result, Exception) and self.run is None:
            # Nothing on screen yet (a link the core refuses): show the defaults.
            self._show_message(f"Not applied — {result}. Showing the default settings.")
            self._restoring = True
            try:
                self.settings.param.update(**state.defaults())
            finally:
                self._restoring = False
        elif isinstance(result, Exception):
            self._show_message(f"Not applied — {result}. Showing the last valid settings.")
        else:
            self._show(run, *result)
        if self._doc is not None:
            if self._wanted is not run:
                _SCENE_POOL.submit(self._scene_work)
            else:
                self._busy = False

    def _show(self, run: Run, scene: compute.SceneData, section: dict) -> None:
        """Update exactly the views whose data changed."""
        if not self._keep_message:
            self._clear_message()
        if scene is not self.scene:
            self.displacement.update(scene)
            self.phase.update(scene)
            self.impact_map.update(scene)
            self._update_badge(scene)
            self.bifurcation.move_marker(run.params.omega,
                                         compute.last(scene.impacts["v"], 200))
        if section is not self.section:
            self.poincare.update(run, section)
        self.run, self.scene, self.section = run, scene, section
        self._update_caption_note()
        self._write_url()

    def _on_load(self) -> None:
        with pn.io.hold(self._doc):
            self._loaded = True
            self._restart_diagram(self._wanted)
            self._write_url()

    def _restart_diagram(self, run: Run) -> None:
        self._diagram_run = run
        self.bifurcation.reset(run)
        self.progress.value = 0
        self.diagram_elapsed = None
        self.diagram_status.object = f"computing {run.bif_n} ω values…"
        if self._loaded:
            self.runner.start(run)

    # -- diagram callbacks (on the event loop) ----------------------------------------

    def _on_chunk(self, gen: int, part: dict, done: int, total: int) -> None:
        self.bifurcation.append(part)
        self.progress.value = int(100 * done / total)
        self.diagram_status.object = f"computing… {done}/{total} ω values"

    def _on_done(self, gen: int, info: dict) -> None:
        elapsed, partial = info["elapsed"], info["partial"]
        self.diagram_elapsed = elapsed
        n = len(self.bifurcation.source.data["omega"])
        run = self._diagram_run
        note = f", {partial} ω values stopped at a work limit" if partial else ""
        if info["done"] < info["total"]:
            self.diagram_status.object = (
                f"stopped at the time limit ({diagram.DIAGRAM_WALL_TIME:g} s): "
                f"{info['done']} of {info['total']} ω values, spread over the range{note}")
            self.bifurcation.finish("partial (time limit)")
            return
        rec = sum(len(p["omega"]) for p in self.bifurcation.parts)
        text = (f"complete: {run.bif_n} ω values, {rec} impacts recorded, {n} distinct "
                f"points drawn, in {elapsed:.2f} s{note}")
        self.diagram_status.object = text
        self.progress.value = 100
        self.bifurcation.finish("complete")

    def _on_diagram_error(self, gen: int, text: str) -> None:
        self.diagram_status.object = f"diagram failed: {text}"
        self.bifurcation.finish("failed")

    # -- badge, messages, URL ----------------------------------------------------------

    def _update_badge(self, scene: compute.SceneData) -> None:
        run = scene.run
        ms = scene.elapsed * 1e3
        warn = ""
        if scene.status != 0:
            warn = f" <span style='color:#b35900'>⚠ {scene.message}</span>"
        self.badge.object = (f"Motion: <b>{scene.label}</b> · {run.method} · computed in "
                             f"{ms:.2f} ms{warn}")

    def _update_caption_note(self) -> None:
        text = self.caption.object
        note = "\n\n*Settings changed since this scene was loaded.*"
        if self._scene_run is None or self.run is None:
            return
        changed = self.run != self._scene_run
        if changed and not text.endswith(note):
            self.caption.object = text + note
        elif not changed and text.endswith(note):
            self.caption.object = text[: -len(note)]

    def _show_message(self, text: str) -> None:
        if self._keep_message and self.message and text not in self.message:
            text = f"{self.message}<br>{text}"     # the link's problems, all of them
        self.message = text
        self.message_pane.object = text
        self.message_pane.visible = True

    def _clear_message(self) -> None:
        if self.message:
            self.message = ""
            self.message_pane.object = ""
            self.message_pane.visible = False

    def _write_url(self) -> None:
        loc = pn.state.location
        if loc is not None and self.run is not None and self._loaded:
            loc.update_query(**state.to_query(self.run))

    # -- on-demand work ------------------------------------------------------------------

    def _on_accuracy(self, event) -> None:
        run = self.run
        self.accuracy_button.disabled = True
        self.accuracy_pane.object = "computing exact, rk4 and rk45…"

        def work():
            try:
                html = accuracy.to_html(accuracy.compare_methods(run))
            except Exception as exc:
                log.warning("accuracy failed: %s: %s", type(exc).__name__, exc)
                html = f"accuracy failed: {type(exc).__name__}: {exc}"
            self._dispatch(lambda: self._accuracy_done(html))

        _ACCURACY_POOL.submit(work)

    def _accuracy_done(self, html: str) -> None:
        self.accuracy_pane.object = html
        self.accuracy_button.disabled = False

    def _filename(self, what: str) -> str:
        p = self.run.params
        return f"{what}_omega{p.omega:g}_r{p.r:g}_c{p.c:g}_g{p.g:g}.csv"

    def _impacts_csv(self):
        self.downloads[0].filename = self._filename("impacts")
        imp = self.scene.impacts
        return _csv({"t": imp["t"], "phase": imp["phase"], "v_before": imp["v"],
                     "v_after": imp["v_after"]})

    def _poincare_csv(self):
        self.downloads[1].filename = self._filename("poincare")
        s = self.section
        return _csv({"t": s["t"], "x": s["x"], "v": s["v"]})

    def _bifurcation_csv(self):
        self.downloads[2].filename = self._filename("bifurcation")
        return _csv(self.bifurcation.table())
