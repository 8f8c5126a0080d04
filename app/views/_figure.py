"""Shared look of the views: figure defaults, presenter mode, hover and ranges."""
from __future__ import annotations

import weakref

from bokeh.models import (AllIndices, AllLabels, BasicTicker, BasicTickFormatter, CDSView,
                          DataRange1d, GlyphRenderer, Grid, LinearAxis, LinearScale, Selection,
                          Title, Tool, Toolbar, UnionRenderers)
from bokeh.plotting import figure

#: Tool sets by kind of view (each tool is a model, box zoom four; a ``Kit``
#: gives the page one of each pan, wheel zoom and reset tool). Box zoom only where a
#: region is worth picking out: the diagram.
TIME_SERIES_TOOLS = "xpan,xwheel_zoom,reset"
CURVE_TOOLS = "pan,wheel_zoom,reset"
POINTS_TOOLS = CURVE_TOOLS
DIAGRAM_TOOLS = "pan,wheel_zoom,box_zoom,reset,save"
LINE = "#1f5fa8"
IMPACT = "#d1495b"
WALL = "#444444"
STICK = "#f2b134"

#: (tick labels, axis labels, title) font sizes, normal and presenter mode (at least
#: 12 px and 18 px: the back row of a classroom reads the ticks).
FONTS = {False: ("12px", "13px", "14px"), True: ("18px", "20px", "22px")}
#: Presenter mode multiplies line widths and marker sizes by these.
LINE_SCALE, SIZE_SCALE = 2.0, 1.6
#: Line widths and marker sizes of each figure's glyphs as built (presenter mode scales
#: these, so toggling it twice gives back the same figure).
_BASE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class Kit:
    """The helper models a session's figures share, one instance of each per document
    (models cannot be shared between documents): scales, tick placement and labels, the
    horizontal grid lines, the sources' selection and its policy (no view selects), the
    "all rows" filter, and the stateless navigation tools (BokehJS makes a tool's view
    per plot; a shared tool only shares its on/off state). Every axis, grid and renderer
    would otherwise get its own instance of each: about 50 models of a page."""

    #: Tools shared by the figures of a kit (by name, as in a figure's ``tools``).
    SHARED_TOOLS = frozenset({"pan", "xpan", "wheel_zoom", "xwheel_zoom", "reset"})

    def __init__(self):
        self.ticker, self.formatter, self.labels = BasicTicker(), BasicTickFormatter(), AllLabels()
        self.policy, self.rows, self.scale = UnionRenderers(), AllIndices(), LinearScale()
        self.selection = Selection()
        # a Grid that names no axis reads its ticks from its ticker and its range from
        # each plot
        self.grid = Grid(dimension=1, ticker=self.ticker)
        self._tools: dict = {}

    def tool(self, name: str):
        """The tool ``name`` (an alias of Bokeh's: "xpan", "box_zoom"...), shared when
        it holds no state of its own."""
        if name not in self.SHARED_TOOLS:
            return Tool.from_string(name)
        if name not in self._tools:
            self._tools[name] = Tool.from_string(name)
        return self._tools[name]

    def axis(self, label) -> LinearAxis:
        return LinearAxis(axis_label=label, ticker=self.ticker, formatter=self.formatter,
                          major_label_policy=self.labels, axis_label_text_font_style="normal")


def make_figure(name: str, title: str, x_label, y_label, *, kit: Kit,
                tools: str = POINTS_TOOLS, toolbar_location="right", x_range=None,
                y_range=None, y_axis_type="linear", grid: bool = True):
    """A figure that fills its cell of the page grid (the page sizes the cells). Its
    toolbar sits inside the frame and shows while the pointer is on the figure, so it
    takes no room from the data.

    Built as ``bokeh.plotting.figure(...)`` builds it, but with the ``kit``'s shared
    models given at construction (figure() makes its own ranges, scales, axes' tickers,
    grids and tools first): draw into it with ``add_glyph``. Horizontal grid lines only
    (``grid``): the vertical ones are a model each and read little."""
    toolbar = Toolbar(tools=[kit.tool(t) for t in tools.split(",") if t], logo=None,
                      autohide=True)
    has_y = y_axis_type is not None
    fig = figure.__new__(figure)
    # Plot's constructor, not figure's: figure() would add axes, grids and tools of its own
    super(figure, fig).__init__(
        name=name, title=Title(text=title), sizing_mode="stretch_both", min_width=120,
        min_height=80, toolbar=toolbar, toolbar_location=toolbar_location,
        toolbar_inner=True, output_backend="canvas",
        x_range=x_range if x_range is not None else DataRange1d(),
        y_range=y_range if y_range is not None else DataRange1d(),
        x_scale=kit.scale, y_scale=kit.scale, below=[kit.axis(x_label)],
        left=[kit.axis(y_label)] if has_y else [], center=[kit.grid] if grid and has_y else [])
    fig._ie_kit = kit
    style(fig, presenter=False)
    return fig


#: Colours a glyph gets where none is given (bokeh.plotting's glyph methods: the
#: palette's first colour; hatch and text black) and alpha where none is given.
_DEFAULT_VISUALS = {"color": "#1f77b4", "alpha": 1.0}
_BLACK = {"hatch_color": "black", "text_color": "black"}


def add_glyph(fig, glyph_class, source, *, name=None, level=None, **props) -> GlyphRenderer:
    """Draw ``glyph_class`` from ``source`` into ``fig`` (made by ``make_figure``) as
    ``fig.<glyph>(...)`` draws it, with the same visual cascade (``color`` and ``alpha``
    stand for each of the glyph's line, fill, hatch and text colours and alphas), but
    with no glyph for non-selected or muted rows (no view selects or mutes) and the
    figure kit's filter, selection and policy."""
    kit = fig._ie_kit
    names = glyph_class.properties()
    given = {t: props.pop(t) for t in ("color", "alpha") if t in props}
    for prop in names:
        feature, _, trait = prop.partition("_")
        if (feature not in ("line", "fill", "hatch", "text", "global") or not trait
                or prop in props):
            continue
        if trait in given and trait not in names:
            props[prop] = given[trait]
        elif prop in _BLACK:
            props[prop] = _BLACK[prop]
        elif trait in _DEFAULT_VISUALS:
            props[prop] = _DEFAULT_VISUALS[trait]
    if source.selected is not kit.selection:
        source.selection_policy = kit.policy
        # (``selected`` is read-only once built; set_from_json is how BokehJS sets it)
        source.set_from_json("selected", kit.selection)
    extra = {"name": name} if name is not None else {}
    if level is not None:
        extra["level"] = level
    renderer = GlyphRenderer(glyph=glyph_class(**props), data_source=source,
                             view=CDSView(filter=kit.rows), nonselection_glyph=None,
                             muted_glyph=None, **extra)
    fig.renderers.append(renderer)
    return renderer


#: Runs in the page: a figure title wider than its frame (a long diagram title in large
#: type on a projector, any long title on a phone) is drawn smaller until it fits, down to
#: three quarters of its size (never below 11 px); where it still does not fit, a shorter
#: text that stays true is drawn instead: first without the settings list (the text
#: between the first ": " and " — ", which the bar and the drawer show), then without
#: its " · " counts from the last, then without the explanation of a closing note
#: ("(settings changed: compute again)" -> "(settings changed)"), then without the
#: head's detail after its first ", " ("Basins at phase 0, 100×100 starts — …" ->
#: "Basins at phase 0 — …"), each fitted the same way (the last one down to 11 px).
#: An x axis label wider than its frame is drawn without its hint after "; " ("time τ (s);
#: zoom out: 250–500 s" -> "time τ (s)"), and gets it back when the frame is wide enough.
#: Only the drawing changes (a silent set, then the text property's own change signal for
#: the title's view: nothing goes back to the server); the text and
#: size the server sets stay the base, so a wider frame gets them back. Checked twice a
#: second (text and frame sizes change without an event BokehJS exposes).
FIT_TITLES_JS = """
if (!window.__ieFitTitles) {
  window.__ieFitTitles = true
  const base = new Map(), fitted = new Map(), text = new Map(), shown = new Map()
  const ctx = document.createElement("canvas").getContext("2d")
  const px = (s) => parseFloat(typeof s === "string" ? s : (s && s.value) || "14")
  const shorter = (full) => {
    const out = [full]
    let t = full
    const dash = t.indexOf(" — "), colon = t.indexOf(": ")
    if (colon >= 0 && dash > colon) { t = t.slice(0, colon) + t.slice(dash); out.push(t) }
    for (let dot = t.lastIndexOf(" · "); dot > 0; dot = t.lastIndexOf(" · ")) {
      const rest = t.indexOf(" — ", dot)
      t = t.slice(0, dot) + (rest > dot ? t.slice(rest) : "")
      out.push(t)
    }
    const note = t.lastIndexOf(" ("), why = t.indexOf(": ", note)
    if (note > 0 && why > note && t.endsWith(")")) { t = t.slice(0, why) + ")"; out.push(t) }
    const comma = t.indexOf(", "), head = t.indexOf(" — ")
    if (comma > 0 && head > comma) out.push(t.slice(0, comma) + t.slice(head))
    return out
  }
  const fit = () => {
    for (const v of Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")) {
      const t = v.model.title
      if (!t || !t.text || v.el.getBoundingClientRect().width === 0) continue
      const now = px(t.text_font_size)
      if (fitted.get(t.id) !== now) base.set(t.id, now)
      if (shown.get(t.id) !== t.text) text.set(t.id, t.text)
      const full = base.get(t.id), room = v.frame.bbox.width
      const texts = shorter(text.get(t.id))
      let pick = texts[texts.length - 1], size = 11
      for (const [i, candidate] of texts.entries()) {
        ctx.font = `${t.text_font_style} ${full}px ${t.text_font}`
        const need = ctx.measureText(candidate).width
        const fits = need > room ? Math.floor(full * room / need) : full
        const least = i === texts.length - 1 ? 11 : Math.max(11, Math.ceil(0.75 * full))
        if (fits >= least) { pick = candidate; size = fits; break }
      }
      if (size !== now || pick !== t.text) {
        fitted.set(t.id, size)
        shown.set(t.id, pick)
        const retext = pick !== t.text
        t.setv({text_font_size: `${size}px`, text: pick}, {silent: true})
        if (retext) t.properties.text.change.emit()    // the title's view remakes its text
        v.invalidate_layout()
        if (retext) setTimeout(() => { t.change.emit(); v.invalidate_layout() }, 100)
      }
    }
  }
  const labels = new Map(), labelShown = new Map()
  const fitLabels = () => {
    for (const v of Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")) {
      if (v.el.getBoundingClientRect().width === 0) continue
      for (const axis of v.model.below) {
        const now = axis.axis_label
        if (typeof now !== "string" || !now) continue
        if (labelShown.get(axis.id) !== now) labels.set(axis.id, now)
        const full = labels.get(axis.id), cut = full.indexOf("; ")
        ctx.font = `${axis.axis_label_text_font_style} ${px(axis.axis_label_text_font_size)}px ${axis.axis_label_text_font}`
        const pick = cut > 0 && ctx.measureText(full).width > v.frame.bbox.width
          ? full.slice(0, cut) : full
        if (pick !== now) {
          labelShown.set(axis.id, pick)
          axis.setv({axis_label: pick}, {silent: true})
          axis.properties.axis_label.change.emit()
          v.invalidate_layout()
          setTimeout(() => { axis.change.emit(); v.invalidate_layout() }, 100)
        }
      }
    }
  }
  setInterval(() => { fit(); fitLabels() }, 500)
  fit()
  fitLabels()
}
"""


def fit_titles(doc) -> None:
    """Install ``FIT_TITLES_JS`` in the page of ``doc`` when it is ready."""
    from bokeh.models import CustomJS

    doc.js_on_event("document_ready", CustomJS(code=FIT_TITLES_JS))


def style(fig, presenter: bool) -> None:
    """Type sizes and line widths of ``fig`` for the screen (False) or a projector."""
    ticks, labels, title = FONTS[bool(presenter)]
    fig.title.text_font_size = title
    for axis in fig.xaxis + fig.yaxis:
        axis.major_label_text_font_size = ticks
        axis.axis_label_text_font_size = labels
        if hasattr(axis.ticker, "desired_num_ticks"):   # large labels need room
            axis.ticker.desired_num_ticks = 4 if presenter else 6
    base = _BASE.setdefault(fig, {})
    for r in fig.renderers:
        if not isinstance(r, GlyphRenderer):
            continue
        for glyph in (r.glyph, r.nonselection_glyph, r.selection_glyph):
            if glyph is None or glyph == "auto":
                continue
            for prop, scale in (("line_width", LINE_SCALE), ("size", SIZE_SCALE)):
                if prop in glyph.properties() and isinstance(getattr(glyph, prop), (int, float)):
                    key = f"{glyph.id}.{prop}"
                    base.setdefault(key, getattr(glyph, prop))
                    setattr(glyph, prop, base[key] * (scale if presenter else 1.0))


def auto_range_over(fig, *renderers) -> None:
    """Auto-ranging (DataRange1d) looks at ``renderers`` only: glyphs moved by the
    animation in the browser then never change a range (a range change would travel
    to the server every frame)."""
    for rng in (fig.x_range, fig.y_range):
        if isinstance(rng, DataRange1d):
            rng.renderers = list(renderers)


def padded(values, include=(), min_span: float = 0.1, pad: float = 0.06):
    """(lo, hi) around ``values`` (plus ``include``), at least ``min_span`` wide, so a
    periodic orbit's single point is not blown up to rounding noise."""
    vals = [float(v) for v in values if v == v] + [float(v) for v in include]
    if not vals:
        return -1.0, 1.0
    lo, hi = min(vals), max(vals)
    span = max(hi - lo, min_span, 0.05 * max(abs(lo), abs(hi)))
    mid = 0.5 * (lo + hi)
    lo, hi = min(lo, mid - span / 2), max(hi, mid + span / 2)
    margin = pad * (hi - lo)
    return lo - margin, hi + margin


def set_range(rng, lo: float, hi: float) -> None:
    """Move a Range1d and make the reset tool return there."""
    rng.update(start=lo, end=hi, reset_start=lo, reset_end=hi)
