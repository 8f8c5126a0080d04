"""The page around the views: a small fixed header (title, scene picker, mode switch,
presenter, PNG), the bar of the four settings a lesson moves (ω, r, c, g), one
information line (caption, motion badge, stability, diagram status, banner), the plot
area of the active mode, and a drawer with every other setting.

Modes (``app.settings.MODES``): explore (the scene's views and the diagram, laid out by
``page_style.EXPLORE_CSS``), compare and research. Each owns the plot area while it is
shown; compare and research are built when first opened (``show_mode``). The drawer's
contents are built when it is first opened, so a page that never opens it never pays
for their Bokeh models.

Widgets are built from ``app.settings.SETTINGS`` (``Setting.widget``: slider, input,
select, radio; ``Setting.group``: the drawer's card). Nothing here computes anything:
the session (app.explorer) calls ``show_*`` with results and gets user actions through
the callbacks it passes in.
"""
from __future__ import annotations

import html
import math
import re
from collections.abc import Mapping

import panel as pn
from bokeh.layouts import column as bokeh_column
import param

from .captions import DEFAULT_CAPTION as CAPTION
from .page_style import (BAR_CSS, BAR_ITEM_CSS, CAPTION_CSS, COMPARE_CSS, CSS, DRAWER_CSS,
                         EXPLORE_CSS, HEADER_CSS, INFO_CSS, LINE_CSS, MESSAGE_CSS, MODAL_CSS,
                         NOTE_CSS, PAGE_CSS, PNG_JS, ROOM_CSS, STAGE_CSS, TOP_CSS)
from .panel_fixes import GRID_COLUMN_CSS, PromptFloatSlider
from .scenes import SCENES
from .settings import BY_NAME, MODES, ON_DIAGRAM, RESEARCH, SETTINGS

DRAWER_WIDTH = 320
#: The diagram status chip's background at ``pct`` per cent done.
PROGRESS = "linear-gradient(90deg, #cfe0f5 {pct}%, transparent {pct}%)"
#: The settings a lesson moves most: always on screen, in the bar under the header.
BAR = ("omega", "r", "c", "g")
#: "i" in a circle, drawn (no font on a lab PC needs to have the character).
INFO_ICON = ('<svg width="1em" height="1em" viewBox="0 0 16 16" aria-hidden="true" '
             'style="vertical-align:-0.15em"><circle cx="8" cy="8" r="7" fill="none" '
             'stroke="currentColor" stroke-width="1.5"/><rect x="7.1" y="6.6" width="1.8" '
             'height="5.4" fill="currentColor"/><circle cx="8" cy="4.4" r="1.1" '
             'fill="currentColor"/></svg>')
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


def _follow_value(settings, s, slider) -> None:
    """The slider spans the teaching range and moves its end out to a value typed beyond
    it (the box takes any number; the session applies it or says why not)."""
    settings.param.watch(lambda event: slider.param.update(**slider_span(s, event.new)),
                         s.name)
    slider.param.update(**slider_span(s, getattr(settings, s.name)))


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
    if s.widget == "slider" and s.name in BAR:
        # for the bar: the symbol as the box's label, the box, the slider beside it (the
        # bar lays the pairs out; no layout model of their own)
        box = pn.widgets.FloatInput.from_param(par, label=s.label.split()[0], format=s.fmt,
                                               start=None, end=None, description=None,
                                               width=118,
                                               stylesheets=[BAR_ITEM_CSS], margin=(2, 4),
                                               css_classes=css + ["ie-bar-box"])
        slider = PromptFloatSlider.from_param(par, label="", start=s.soft[0], end=s.soft[1],
                                              step=s.step, show_value=False,
                                              sizing_mode="stretch_width", margin=(12, 12, 0, 4),
                                              css_classes=css + ["ie-bar-slider"])
        _follow_value(settings, s, slider)
        return box, (box, slider)
    if s.widget == "radio":
        radio = pn.widgets.RadioButtonGroup.from_param(
            par, name="", options={c.capitalize(): c for c in s.choices}, description=None,
            css_classes=css, margin=(2, 4))
        return radio, radio
    if s.widget == "slider":
        box = pn.widgets.FloatInput.from_param(par, label=s.label, format=s.fmt, start=None,
                                               end=None, description=None,
                                               sizing_mode="stretch_width")
        slider = PromptFloatSlider.from_param(par, label="", start=s.soft[0], end=s.soft[1],
                                              step=s.step, show_value=False,
                                              sizing_mode="stretch_width", margin=(0, 10))
        _follow_value(settings, s, slider)
        return box, pn.Column(box, slider, css_classes=css, sizing_mode="stretch_width")
    if s.widget == "toggle":
        toggle = pn.widgets.Toggle.from_param(par, label=s.label, color="default", width=100,
                                              margin=(2, 4), css_classes=css)
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
        head = pn.pane.HTML(f"<b title=\"{docs}\">{title} {INFO_ICON}</b>", margin=(5, 10, 0, 10),
                            css_classes=["ie-group"])
        return pn.Column(head, *objects, sizing_mode="stretch_width")
    card = pn.layout.Card(title=title, collapsed=True, sizing_mode="stretch_width")

    def opened(event):
        if not event.new and not card.objects:
            card.objects = objects
    card.param.watch(opened, "collapsed")
    return card


class _Made:
    """Each setting's (widget, page item), built the first time either is asked for: the
    drawer's and research's settings cost nothing on a page that never shows them."""

    def __init__(self, settings):
        self._settings, self._made = settings, {}
        self.widget, self.item = _Lazy(self, 0), _Lazy(self, 1)

    def get(self, name: str):
        if name not in self._made:
            self._made[name] = make_widget(self._settings, BY_NAME[name])
        return self._made[name]


class _Lazy(Mapping):
    """Setting name -> one half of ``_Made.get`` (a read-only mapping over every setting)."""

    def __init__(self, made: _Made, half: int):
        self._made, self._half = made, half

    def __getitem__(self, name: str):
        if name not in BY_NAME:
            raise KeyError(name)
        return self._made.get(name)[self._half]

    def __iter__(self):
        return iter(BY_NAME)

    def __len__(self) -> int:
        return len(BY_NAME)


class Controls:
    """Widgets, panes and layout of one session's page. ``rooms`` maps the modes other
    than explore to a function that builds that mode's plot area (called when the mode
    is first shown)."""

    def __init__(self, settings, views, *, on_scene, on_accuracy, downloads, on_reset,
                 rooms=None):
        made = _Made(settings)
        self.widgets, self._items = made.widget, made.item
        self._downloads = downloads
        self._room_builders = dict(rooms or {})
        self.rooms: dict = {}
        self.mode = None
        self.message = ""
        self.message_pane = pn.pane.HTML("", visible=False, css_classes=["ie-message"],
                                         stylesheets=[MESSAGE_CSS], sizing_mode="stretch_width",
                                         margin=0)
        self.badge = pn.pane.HTML("", css_classes=["ie-badge"], stylesheets=[CSS, LINE_CSS],
                                  margin=(0, 5))
        self.stability = NamedHTML("", model_name=STABILITY_NAME,
                                   css_classes=["ie-stability"], stylesheets=[CSS, LINE_CSS],
                                   margin=(0, 5))
        self.caption = pn.pane.Markdown(CAPTION, css_classes=["ie-caption"], margin=(0, 5),
                                        stylesheets=[CAPTION_CSS])
        self.scene_picker = pn.widgets.Select(
            options={PICK: PICK, **{sc.label: sc.key for sc in SCENES}}, value=PICK,
            css_classes=["ie-scene"], width=180, margin=(2, 4),
            description="Load the settings of one of the paper's figures")
        self._scene_shown = PICK
        self.scene_picker.param.watch(lambda event: self._picked(event.new, on_scene), "value")
        self.reset_button = pn.widgets.Button(
            label="Reset", width=64, margin=(2, 4), css_classes=["ie-reset"],
            description="Back to the settings of the scene loaded (or the paper's defaults)")
        self.reset_button.on_click(lambda event: on_reset())
        self.diagram_status = NamedHTML("", model_name=STATUS_NAME,
                                        css_classes=["ie-diagram-status"],
                                        stylesheets=[CSS, LINE_CSS], margin=(0, 5))
        self.accuracy_button = pn.widgets.Button(
            label="Compare methods", color="primary", sizing_mode="stretch_width",
            description="Run exact, rk4 and rk45 on the current scene and compare their "
                        "impacts and run times (not recomputed on slider moves).")
        self.accuracy_button.on_click(lambda event: on_accuracy())
        self.accuracy_pane = self.accuracy_modal = None      # built on first use
        self.sidebar_toggle = pn.widgets.Toggle(label="☰ Settings", value=False, width=104,
                                                margin=(2, 4), css_classes=["ie-sidebar-toggle"])
        self.png_button = pn.widgets.Button(label="Save PNG", width=90, margin=(2, 4),
                                            css_classes=["ie-png"])
        self.png_button.js_on_click(code=PNG_JS)
        self.pin_toggle = pn.widgets.Toggle(label="Pin maps", width=86, margin=(2, 4),
                                            css_classes=["ie-pin"])
        self.layout = self._layout(views)

    def _picked(self, key, on_scene) -> None:
        if key != self._scene_shown:
            on_scene(None if key == PICK else key)

    def show_scene(self, key: str | None) -> None:
        """The picker shows the scene loaded (None: the paper's defaults)."""
        self._scene_shown = PICK if key is None else key
        self.scene_picker.value = self._scene_shown

    # -- layout ------------------------------------------------------------------------

    def _group(self, title: str) -> list:
        """The widgets of one drawer card: sliders and selects on their own line,
        half-width inputs two to a row."""
        out, half = [], []
        for s in (s for s in SETTINGS if s.group == title and s.name not in BAR):
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
        """One view in the explore grid, with the views drawn under it (sharing its
        width; each keeps its own height)."""
        root = view.root if not under else bokeh_column(
            view.root, *(u.root for u in under), sizing_mode="stretch_both")
        # (a Bokeh pane hands the page the model itself: the grid's classes go on it)
        root.css_classes = [*root.css_classes, "ie-cell", f"ie-cell-{view.key}"]
        return pn.pane.Bokeh(root, sizing_mode="stretch_both", margin=0)

    @staticmethod
    def _notes(views):
        """The page's title and "What am I looking at?": one or two sentences per view,
        folded (one model)."""
        items = []
        for v in views:
            title, note = ((v.figure.title.text, v.note) if v.note else
                           EXTRA_NOTES.get(v.key, ("", "")))
            if note:
                items.append(f"<p><b>{title}</b>: {note}</p>")
        return pn.pane.HTML("<b class='ie-title'>Impact Explorer</b><details><summary "
                            f"title='What am I looking at?'>{INFO_ICON}<span "
                            "class='ie-notes-label'> What am I looking at?</span></summary>"
                            "<div>" + "".join(items) + "</div></details>",
                            stylesheets=[NOTE_CSS], margin=(2, 5), css_classes=["ie-notes"])

    def _layout(self, views):
        # the bar comes first in the page (ω's box is the first Tab stop), the header
        # is drawn above it (TOP_CSS)
        self.bar = bar = pn.Row(*(w for n in BAR for w in self._items[n]), css_classes=["ie-bar"],
                     stylesheets=[BAR_CSS], sizing_mode="stretch_width", margin=0)
        self._items["branches"].name = "Branches"    # short, in the header (its doc: drawer)
        self.notes = self._notes(views)
        self.header = pn.Row(
            self.sidebar_toggle, self.notes, self.scene_picker, self.reset_button,
            *(self._items[s.name] for s in SETTINGS if s.group in ("header", ON_DIAGRAM)),
            self.pin_toggle, self.png_button,
            css_classes=["ie-header"], stylesheets=[HEADER_CSS], sizing_mode="stretch_width",
            margin=0)
        self.top = top = pn.Column(bar, self.header, css_classes=["ie-top"], stylesheets=[TOP_CSS],
                        sizing_mode="stretch_width", margin=0)
        # the message pane is in the line from the start: inserting it later re-sends the
        # line's other models in full, which a Bokeh client warns about
        self.info = info = pn.Row(self.message_pane, self.caption, self.badge, self.stability,
                      self.diagram_status, css_classes=["ie-info"],
                      stylesheets=[INFO_CSS], sizing_mode="stretch_width", margin=0)
        cells = [v for v in views if v.figure is not None and not v.under]
        self.grid = pn.Column(*(self._cell(v, [u for u in views if u.under == v.key])
                                for v in cells),
                              stylesheets=[GRID_COLUMN_CSS, EXPLORE_CSS],
                              sizing_mode="stretch_both", css_classes=["ie-explore"], margin=0)
        self.rooms["explore"] = self.grid
        self.stage = pn.Column(self.grid, css_classes=["ie-stage"], stylesheets=[STAGE_CSS],
                               sizing_mode="stretch_both", margin=0)
        self.drawer = pn.Column(width=DRAWER_WIDTH, visible=False, stylesheets=[DRAWER_CSS],
                                css_classes=["ie-drawer", "ie-sidebar"], margin=0)
        self.sidebar_toggle.param.watch(lambda e: self.show_drawer(e.new), "value")
        self.main = pn.Column(top, info, self.stage, sizing_mode="stretch_both",
                              stylesheets=[PAGE_CSS], css_classes=["ie-page"], margin=0)
        return self.main

    def show_drawer(self, visible: bool) -> None:
        """Open (building its contents the first time) or close the settings drawer."""
        if visible and not self.drawer.objects:
            groups = [g for g in dict.fromkeys(s.group for s in SETTINGS)
                      if g not in ("header", RESEARCH, ON_DIAGRAM)]
            self.main.append(self.drawer)
            close = pn.widgets.Button(label="✕ Close", width=90, margin=(4, 10),
                                      css_classes=["ie-drawer-close"])
            close.on_click(lambda event: self.show_drawer(False))
            self.drawer.objects = [
                close, *(_card(g, self._group(g), open_=i < 2) for i, g in enumerate(groups)),
                _card("Downloads", self._downloads.widgets),
                _card("Accuracy", [self.accuracy_button])]
        self.drawer.visible = visible
        if self.sidebar_toggle.value != visible:
            self.sidebar_toggle.value = visible

    def present(self, on: bool) -> None:
        """Presenter mode: the information line in large type, the drawer closed, the
        bar's four boxes in the header's line (TOP_CSS), so the figures keep their room."""
        for pane in (self.top, self.bar, self.header, self.notes, self.info, self.caption,
                     self.badge, self.stability, self.diagram_status):
            classes = [c for c in pane.css_classes if c != "ie-big"]
            pane.css_classes = classes + ["ie-big"] if on else classes
        if on:
            self.show_drawer(False)

    def show_mode(self, mode: str) -> None:
        """Give the plot area to ``mode`` (building its room the first time)."""
        if mode not in MODES or mode == self.mode:
            return
        if mode not in self.rooms:
            room = self._room_builders[mode]()
            room.css_classes = [*room.css_classes, "ie-room", f"ie-{mode}"]
            room.stylesheets = [*room.stylesheets, ROOM_CSS]
            self.rooms[mode] = room
            self.stage.append(room)
        for name, room in self.rooms.items():       # (a class: the grid's CSS sets display)
            classes = [c for c in room.css_classes if c != "ie-off"]
            room.css_classes = classes if name == mode else classes + ["ie-off"]
        self.mode = mode

    def compare_room(self, figures):
        """Compare mode's plot area: a heading and the small multiples, five columns of
        two rows on a wide screen (COMPARE_CSS)."""
        for fig in figures:
            fig.css_classes = [*fig.css_classes, "ie-cell"]
        grid = pn.Column(*(pn.pane.Bokeh(f, sizing_mode="stretch_both", margin=0)
                           for f in figures),
                         stylesheets=[GRID_COLUMN_CSS, COMPARE_CSS], sizing_mode="stretch_both",
                         css_classes=["ie-compare-plots"], margin=0)
        return pn.Column(
            pn.pane.HTML("<b>Side by side:</b> Fig. 3 (a)–(f), diagrams for r = 0 … 0.9; "
                         "Fig. 7 (a)–(d), Poincaré sections at ω = 2.8 — shared, fixed axes",
                         css_classes=["ie-compare-head"], stylesheets=[CSS, LINE_CSS],
                         sizing_mode="stretch_width", margin=(0, 5)),
            grid, sizing_mode="stretch_both", css_classes=["ie-compare-panel"], margin=0)

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
        """The diagram's status line (``bifurcation_status``); its background fills
        from the left as the diagram is computed (no progress bar model)."""
        self.diagram_status.object = text
        if total or done == 0:
            pct = int(100 * (done or 0) / total) if total else 0
            self.diagram_status.styles = {"background": PROGRESS.format(pct=pct)}

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
