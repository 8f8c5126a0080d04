"""The page around the views: sidebar widgets (one per setting), scene buttons, message,
badge, caption, diagram progress and status, and the layout that holds them.

Widgets are built from ``app.settings.SETTINGS`` (``Setting.widget``: slider, input or
select; ``Setting.group``: the sidebar card). Nothing here computes anything: the
session (app.explorer) calls ``show_*`` with results and gets user actions through the
callbacks it passes in.
"""
from __future__ import annotations

import html

import panel as pn
import param

from .panel_fixes import PromptFloatSlider
from .scenes import SCENES
from .settings import ON_DIAGRAM, RESEARCH, SETTINGS

SIDEBAR_WIDTH = 310
STATUS_NAME = "bifurcation_status"
STABILITY_NAME = "stability_readout"
CAPTION = ("Paper defaults: m = 1, c = 0.05, k = 1, g = 0, r = 0.8, ω = 2. "
           "Pick a scene of the paper or move a slider.")
PICK = "Pick a scene of the paper…"
CHANGED_NOTE = "\n\n*Settings changed since this scene was loaded.*"
CSS = """
.ie-badge {font-size: 16px;}
.ie-badge b {color: #1f5fa8;}
.ie-stability {font-size: 14px;}
.ie-accuracy td, .ie-accuracy th {padding: 2px 6px; font-size: 12px; text-align: left;}
"""


class NamedHTML(pn.pane.HTML):
    """An HTML pane whose Bokeh model carries ``model_name``, so that checks outside the
    app find it with ``document.get_model_by_name``."""

    model_name = param.String(default="")

    _rename = {**pn.pane.HTML._rename, "model_name": None}

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        model.name = self.model_name
        return model


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
        box = pn.widgets.FloatInput.from_param(par, label=s.label, format=s.fmt,
                                               description=None, sizing_mode="stretch_width")
        slider = PromptFloatSlider.from_param(par, label="", start=s.soft[0], end=s.soft[1],
                                              step=s.step, show_value=False,
                                              sizing_mode="stretch_width", margin=(0, 10))
        return box, pn.Column(box, slider, css_classes=css, sizing_mode="stretch_width")
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

    def __init__(self, settings, views, *, on_scene, on_accuracy, downloads):
        made = {s.name: make_widget(settings, s) for s in SETTINGS}
        self.widgets = {name: widget for name, (widget, _) in made.items()}
        self._items = {name: item for name, (_, item) in made.items()}
        self.message = ""
        self.message_pane = pn.pane.Alert("", alert_type="warning", visible=False,
                                          css_classes=["ie-message"],
                                          sizing_mode="stretch_width")
        self.badge = pn.pane.HTML("", css_classes=["ie-badge"], sizing_mode="stretch_width",
                                  stylesheets=[CSS])
        self.stability = NamedHTML("", model_name=STABILITY_NAME,
                                   css_classes=["ie-stability"], stylesheets=[CSS],
                                   sizing_mode="stretch_width")
        self.caption = pn.pane.Markdown(CAPTION, css_classes=["ie-caption"],
                                        sizing_mode="stretch_width")
        self.scene_picker = pn.widgets.Select(
            label="Scenes of the paper", options={PICK: PICK, **{sc.label: sc.key for sc in SCENES}},
            value=PICK, css_classes=["ie-scene"], width=260, margin=(5, 10))
        self.scene_picker.param.watch(lambda event: self._picked(event.new, on_scene), "value")
        self.progress = pn.indicators.Progress(value=0, max=100, width=200, height=14,
                                               bar_color="primary", margin=(8, 10))
        self.diagram_status = NamedHTML("", model_name=STATUS_NAME,
                                        css_classes=["ie-diagram-status"],
                                        sizing_mode="stretch_width")
        self.accuracy_button = pn.widgets.Button(
            label="Compare methods", color="primary", sizing_mode="stretch_width",
            description="Run exact, rk4 and rk45 on the current scene and compare their "
                        "impacts and run times (not recomputed on slider moves).")
        self.accuracy_button.on_click(lambda event: on_accuracy())
        self.accuracy_pane = pn.pane.HTML("", css_classes=["ie-accuracy-out"],
                                          stylesheets=[CSS], sizing_mode="stretch_width")
        self.layout = self._layout(views, downloads)

    def _picked(self, key, on_scene) -> None:
        if key != PICK:
            on_scene(key)
            self.scene_picker.value = PICK      # the same scene can be picked again

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

    def _layout(self, views, downloads):
        groups = [g for g in dict.fromkeys(s.group for s in SETTINGS)
                  if g not in (RESEARCH, ON_DIAGRAM)]
        sidebar = pn.Column(
            *(_card(g, self._group(g), open_=i < 2) for i, g in enumerate(groups)),
            _card("Downloads", downloads.widgets),
            _card("Accuracy", [self.accuracy_button, self.accuracy_pane]),
            width=SIDEBAR_WIDTH)
        pane = dict(sizing_mode="stretch_width")
        grid = pn.GridBox(*(pn.pane.Bokeh(v.figure, **pane) for v in views
                            if not v.wide and v.figure is not None),
                          ncols=2, sizing_mode="stretch_width")
        main = self.main = pn.Column(
            pn.pane.Markdown("## Impact Explorer — forced oscillator with a rigid endstop",
                             margin=(0, 10)),
            self.message_pane,
            self.scene_picker,
            self.caption,
            self.badge,
            self.stability,
            grid,
            self.progress,
            self.diagram_status,
            *(self._items[s.name] for s in SETTINGS if s.group == ON_DIAGRAM),
            *(pn.pane.Bokeh(v.figure, **pane) for v in views
              if v.wide and v.figure is not None),
            sizing_mode="stretch_width")
        return pn.Row(sidebar, main, sizing_mode="stretch_width")

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
        self.badge.object = (f"Motion: <b>{scene.label}</b> · {scene.run.method} · computed "
                             f"in {scene.elapsed * 1e3:.2f} ms{warn}")

    def show_stability(self, html: str | None) -> None:
        """The stability readout (``stability_readout``); None while it is computed."""
        self.stability.object = html or "Stability: computing…"

    def show_caption(self, text: str) -> None:
        self.caption.object = text

    def mark_caption(self, changed: bool) -> None:
        """Note on the scene's caption whether the settings moved away from it."""
        text = self.caption.object
        if changed and not text.endswith(CHANGED_NOTE):
            self.caption.object = text + CHANGED_NOTE
        elif not changed and text.endswith(CHANGED_NOTE):
            self.caption.object = text[: -len(CHANGED_NOTE)]

    def show_diagram(self, text: str, done: int | None = None, total: int | None = None):
        """The diagram's status line (``bifurcation_status``) and progress bar."""
        self.diagram_status.object = text
        if total:
            self.progress.value = int(100 * done / total)
        elif done == 0:
            self.progress.value = 0

    def show_accuracy(self, html: str | None) -> None:
        """The accuracy table; None while it is computed."""
        self.accuracy_button.disabled = html is None
        self.accuracy_pane.object = html or "computing exact, rk4 and rk45…"
