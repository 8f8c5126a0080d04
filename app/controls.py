"""The page around the views: sidebar widgets (one per setting), scene picker, message,
badge, caption, diagram progress and status, presenter / compare / pin / PNG controls,
and the layout that holds them (a grid that fills a projector's screen).

Widgets are built from ``app.settings.SETTINGS`` (``Setting.widget``: slider, input or
select; ``Setting.group``: the sidebar card). Nothing here computes anything: the
session (app.explorer) calls ``show_*`` with results and gets user actions through the
callbacks it passes in.
"""
from __future__ import annotations

import html
import math
import re

import panel as pn
from bokeh.layouts import column as bokeh_column
import param

from .captions import DEFAULT_CAPTION as CAPTION
from .page_style import (CAPTION_CSS, CELL_CSS, CSS, GRID_CSS, LINE_CSS, MAIN_CSS,
                         MODAL_CSS, NOTE_CSS, PAGE_CSS, PNG_JS, SIDEBAR_CSS)
from .panel_fixes import GRID_COLUMN_CSS, PromptFloatSlider
from .scenes import SCENES
from .settings import ON_DIAGRAM, RESEARCH, SETTINGS

SIDEBAR_WIDTH = 300
STATUS_NAME = "bifurcation_status"
STABILITY_NAME = "stability_readout"
PICK = "Paper defaults"
#: The diagram's note (its view's file belongs to the diagram's owners).
EXTRA_NOTES = {"bifurcation": (
    "Bifurcation diagram", "For each ω on the axis, the impact velocities after the "
    "transient. One dot per ω: one impact per period; several: period-n or multi-impact "
    "motion; a smear: chaos. The red line is the current ω.")}


def _line(markup: str) -> str:
    """``markup`` as one line of fixed height (LINE_CSS), its whole text as hover text."""
    title = html.escape(html.unescape(re.sub(r"<[^>]+>", "", markup)), quote=True)
    return f'<div class="ie-line" title="{title}">{markup}</div>'


class NamedHTML(pn.pane.HTML):
    """An HTML pane whose Bokeh model carries ``model_name``, so that checks outside the
    app find it with ``document.get_model_by_name``."""

    model_name = param.String(default="")

    _rename = {**pn.pane.HTML._rename, "model_name": None}

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        model.name = self.model_name
        return model


def slider_span(s, value) -> dict:
    """Start and end of setting ``s``'s slider: its teaching range, widened to hold
    ``value`` (a number typed beyond it)."""
    lo, hi = s.soft
    if isinstance(value, (int, float)) and math.isfinite(value):
        lo, hi = min(lo, value), max(hi, value)
    return {"start": lo, "end": hi}


def make_widget(settings, s):
    """(widget, page item) editing setting ``s`` of ``settings``: the widget holds the
    value as typed (a number box, select), the item is what the page shows.

    Light on purpose (a page has ~20 of them): a slider is a labelled number box over a
    plain slider, both bound to the same setting (no composite widget, no JS links).
    Only selects carry a tooltip model; the docs of a card's settings are the hover
    text of its title (see ``_card``).
    """
    par = settings.param[s.name]
    css = [f"ie-w-{s.name}"]
    if s.widget == "slider":
        # the box takes any number (the session applies it or says why not); the
        # slider spans the teaching range, and its end moves out to a value beyond
        box = pn.widgets.FloatInput.from_param(par, label=s.label, format=s.fmt, start=None,
                                               end=None, description=None,
                                               sizing_mode="stretch_width")
        slider = PromptFloatSlider.from_param(par, label="", start=s.soft[0], end=s.soft[1],
                                              step=s.step, show_value=False,
                                              sizing_mode="stretch_width", margin=(0, 10))
        settings.param.watch(lambda event: slider.param.update(**slider_span(s, event.new)),
                             s.name)
        slider.param.update(**slider_span(s, getattr(settings, s.name)))
        return box, pn.Column(box, slider, css_classes=css, sizing_mode="stretch_width")
    if s.widget == "toggle":
        toggle = pn.widgets.Toggle.from_param(par, label=s.label, color="default", width=100,
                                              margin=(4, 5), css_classes=css)
        return toggle, toggle
    common = dict(label=s.label, sizing_mode="stretch_width", css_classes=css)
    if s.widget == "checkbox":
        box = pn.widgets.Checkbox.from_param(par, name=s.label, css_classes=css,
                                             margin=(8, 10))
        return box, box
    if s.widget == "select":
        select = pn.widgets.Select.from_param(par, description=s.doc, **common)
        return select, select
    cls = pn.widgets.IntInput if s.kind == "integer" else pn.widgets.FloatInput
    extra = {"format": s.fmt} if s.fmt else {}
    box = cls.from_param(par, description=None, **common, **extra)
    return box, box


def _card(title: str, objects: list, open_: bool = False):
    """A sidebar group. Open ones are a titled column whose title's hover text holds
    the docs of its settings; a collapsed card gets its contents (and their Bokeh
    models) only when first opened, so a page that never opens it never pays for them."""
    if open_:
        docs = html.escape("\n".join(f"{s.label.split()[0]}: {s.doc}" for s in SETTINGS
                                      if s.group == title), quote=True)
        head = pn.pane.HTML(f"<b title=\"{docs}\">{title} ⓘ</b>", margin=(5, 10, 0, 10),
                            css_classes=["ie-group"])
        return pn.Column(head, *objects, sizing_mode="stretch_width")
    card = pn.layout.Card(title=title, collapsed=True, sizing_mode="stretch_width")

    def opened(event):
        if not event.new and not card.objects:
            card.objects = objects
    card.param.watch(opened, "collapsed")
    return card


class Controls:
    """Widgets, panes and layout of one session's page."""

    def __init__(self, settings, views, *, on_scene, on_accuracy, downloads, on_reset):
        made = {s.name: make_widget(settings, s) for s in SETTINGS}
        self.widgets = {name: widget for name, (widget, _) in made.items()}
        self._items = {name: item for name, (_, item) in made.items()}
        self.message = ""
        self.message_pane = pn.pane.Alert("", alert_type="warning", visible=False,
                                          css_classes=["ie-message"],
                                          sizing_mode="stretch_width", margin=(0, 5))
        self.badge = pn.pane.HTML("", css_classes=["ie-badge"], stylesheets=[CSS, LINE_CSS],
                                  margin=(0, 5), sizing_mode="stretch_width")
        self.stability = NamedHTML("", model_name=STABILITY_NAME,
                                   css_classes=["ie-stability"], stylesheets=[CSS, LINE_CSS],
                                   margin=(0, 5), sizing_mode="stretch_width")
        self.caption = pn.pane.Markdown(CAPTION, css_classes=["ie-caption"],
                                        sizing_mode="stretch_width", margin=(0, 5),
                                        stylesheets=[CAPTION_CSS])
        self.scene_picker = pn.widgets.Select(
            options={PICK: PICK, **{sc.label: sc.key for sc in SCENES}}, value=PICK,
            css_classes=["ie-scene"], width=190, margin=(4, 5),
            description="Load the settings of one of the paper's figures")
        self._scene_shown = PICK
        self.scene_picker.param.watch(lambda event: self._picked(event.new, on_scene), "value")
        self.reset_button = pn.widgets.Button(
            label="Reset", width=70, margin=(4, 5), css_classes=["ie-reset"],
            description="Back to the settings of the scene loaded (or the paper's defaults)")
        self.reset_button.on_click(lambda event: on_reset())
        self.progress = pn.indicators.Progress(value=0, max=100, width=120, height=12,
                                               bar_color="primary", margin=(6, 5))
        self.diagram_status = NamedHTML("", model_name=STATUS_NAME,
                                        css_classes=["ie-diagram-status"],
                                        sizing_mode="stretch_width", margin=(0, 5))
        self.accuracy_button = pn.widgets.Button(
            label="Compare methods", color="primary", sizing_mode="stretch_width",
            description="Run exact, rk4 and rk45 on the current scene and compare their "
                        "impacts and run times (not recomputed on slider moves).")
        self.accuracy_button.on_click(lambda event: on_accuracy())
        self.accuracy_pane = self.accuracy_modal = None      # built on first use
        self.sidebar_toggle = pn.widgets.Toggle(label="☰ Settings", value=True, width=110,
                                                margin=(4, 5), css_classes=["ie-sidebar-toggle"])
        self.png_button = pn.widgets.Button(label="Save PNG", width=100, margin=(4, 5),
                                            css_classes=["ie-png"],
                                            description="All views as one PNG image")
        self.png_button.js_on_click(code=PNG_JS)
        self.compare_toggle = pn.widgets.Toggle(label="Compare", width=100, margin=(4, 5),
                                                css_classes=["ie-compare"])
        self.pin_toggle = pn.widgets.Toggle(label="Pin maps", width=100, margin=(4, 5),
                                            css_classes=["ie-pin"])
        self._compare_panel = None
        self.layout = self._layout(views, downloads)

    def _picked(self, key, on_scene) -> None:
        if key != self._scene_shown:
            on_scene(None if key == PICK else key)

    def show_scene(self, key: str | None) -> None:
        """The picker shows the scene loaded (None: the paper's defaults)."""
        self._scene_shown = PICK if key is None else key
        self.scene_picker.value = self._scene_shown

    # -- layout ------------------------------------------------------------------------

    def _group(self, title: str) -> list:
        """The widgets of one sidebar card: sliders and selects on their own line,
        half-width inputs two to a row."""
        out, half = [], []
        for s in (s for s in SETTINGS if s.group == title):
            if s.half:
                half.append(self._items[s.name])
                if len(half) == 2:
                    out.append(pn.Row(*half))
                    half = []
                continue
            out.append(self._items[s.name])
        if half:
            out.append(pn.Row(*half))
        return out

    def _cell(self, view, under=()):
        """One view in the grid, with the views drawn under it (sharing its width; each
        keeps its own height)."""
        if not under:
            return pn.pane.Bokeh(view.root, sizing_mode="stretch_both", stylesheets=[CELL_CSS],
                                 css_classes=[f"ie-cell-{view.key}"])
        root = bokeh_column(view.root, *(u.root for u in under), sizing_mode="stretch_both")
        return pn.pane.Bokeh(root, sizing_mode="stretch_both", stylesheets=[CELL_CSS],
                             css_classes=[f"ie-cell-{view.key}"])

    @staticmethod
    def _notes(views):
        """"What am I looking at?": one or two sentences per view, folded (one model)."""
        items = []
        for v in views:
            title, note = ((v.figure.title.text, v.note) if v.note else
                           EXTRA_NOTES.get(v.key, ("", "")))
            if note:
                items.append(f"<p><b>{title}</b>: {note}</p>")
        return pn.pane.HTML("<details><summary>ⓘ What am I looking at?</summary><div>"
                            + "".join(items) + "</div></details>", stylesheets=[NOTE_CSS],
                            margin=(8, 5), css_classes=["ie-notes"])

    def _layout(self, views, downloads):
        groups = [g for g in dict.fromkeys(s.group for s in SETTINGS)
                  if g not in ("header", RESEARCH, ON_DIAGRAM)]
        self.sidebar = sidebar = pn.Column(
            *(_card(g, self._group(g), open_=i < 2) for i, g in enumerate(groups)),
            _card("Downloads", downloads.widgets),
            _card("Accuracy", [self.accuracy_button]),
            width=SIDEBAR_WIDTH, stylesheets=[SIDEBAR_CSS], css_classes=["ie-sidebar"])
        self.sidebar_toggle.link(sidebar, value="visible")
        header = pn.FlexBox(
            self.sidebar_toggle,
            pn.pane.HTML("<b style='font-size:17px'>Impact Explorer</b>", margin=(8, 5)),
            self.scene_picker, self.reset_button,
            *(self._items[s.name] for s in SETTINGS if s.group in ("header", ON_DIAGRAM)),
            self.compare_toggle, self.pin_toggle, self.png_button, self._notes(views),
            self.progress, self.diagram_status,
            sizing_mode="stretch_width", align_items="center", flex_wrap="wrap")
        cells = [v for v in views if v.figure is not None and not v.under]
        self.grid = pn.Column(*(self._cell(v, [u for u in views if u.under == v.key])
                                for v in cells),
                              stylesheets=[GRID_COLUMN_CSS, GRID_CSS],
                              sizing_mode="stretch_both", css_classes=["ie-grid"])
        self.main = main = pn.Column(
            header, self.message_pane, self.caption, self.badge, self.stability, self.grid,
            stylesheets=[MAIN_CSS], sizing_mode="stretch_both", css_classes=["ie-main"])
        return pn.Row(sidebar, main, sizing_mode="stretch_both", stylesheets=[PAGE_CSS],
                      css_classes=["ie-page"])

    def show_compare(self, root, visible: bool) -> None:
        """The compare panel (built on first use) over the page, or hide it."""
        if self._compare_panel is None:
            if not visible:
                return
            close = pn.widgets.Button(label="Close", width=80, css_classes=["ie-compare-close"])
            close.on_click(lambda event: setattr(self.compare_toggle, "value", False))
            self._compare_panel = pn.Column(
                pn.Row(pn.pane.Markdown(
                    "### Side by side: Fig. 3 (a)–(f), diagrams for r = 0 … 0.9; Fig. 7 "
                    "(a)–(d), Poincaré sections at ω = 2.8 — shared, fixed axes",
                    margin=(0, 5)), close),
                pn.pane.Bokeh(root, sizing_mode="stretch_width"),
                stylesheets=[MODAL_CSS], css_classes=["ie-compare-panel"])
            self.main.append(self._compare_panel)
        self._compare_panel.visible = visible

    def add_research(self, card) -> None:
        """The research card, last on the page (below the six main figures)."""
        self.main.append(card)

    # -- what the session shows --------------------------------------------------------

    def show_message(self, text: str, keep: bool = False) -> None:
        """Show ``text``; with ``keep``, add it to the message shown (a link's problems,
        all of them)."""
        if keep and self.message and text not in self.message:
            text = f"{self.message}<br>{text}"
        self.message = text
        self.message_pane.object = text
        self.message_pane.visible = True

    def clear_message(self) -> None:
        if self.message:
            self.message = ""
            self.message_pane.object = ""
            self.message_pane.visible = False

    def show_badge(self, scene) -> None:
        warn = ""
        if scene.status != 0:
            warn = f" <span style='color:#b35900'>⚠ {scene.message}</span>"
        self.badge.object = _line(f"Motion: <b>{scene.label}</b> · {scene.run.method} · "
                                  f"computed in {scene.elapsed * 1e3:.2f} ms{warn}")

    def show_stability(self, html: str | None) -> None:
        """The stability readout (``stability_readout``); None while it is computed."""
        self.stability.object = _line(html or "Stability: computing…")

    def show_caption(self, text: str) -> None:
        self.caption.object = text

    def show_diagram(self, text: str, done: int | None = None, total: int | None = None):
        """The diagram's status line (``bifurcation_status``) and progress bar."""
        self.diagram_status.object = text
        if total:
            self.progress.value = int(100 * done / total)
        elif done == 0:
            self.progress.value = 0

    def show_accuracy(self, html: str | None) -> None:
        """The accuracy table, in a full-width panel over the page; None while it is
        computed."""
        if self.accuracy_modal is None:
            self.accuracy_pane = pn.pane.HTML("", css_classes=["ie-accuracy-out"],
                                              stylesheets=[CSS], sizing_mode="stretch_width")
            close = pn.widgets.Button(label="Close", width=80,
                                      css_classes=["ie-accuracy-close"])
            self.accuracy_modal = pn.Column(
                pn.Row(pn.pane.Markdown("### Accuracy of the three methods on this scene",
                                        margin=(0, 5)), close),
                self.accuracy_pane, stylesheets=[MODAL_CSS], css_classes=["ie-accuracy-modal"])
            close.on_click(lambda event: setattr(self.accuracy_modal, "visible", False))
            self.main.append(self.accuracy_modal)
        self.accuracy_button.disabled = html is None
        self.accuracy_pane.object = html or "computing exact, rk4 and rk45…"
        self.accuracy_modal.visible = True
