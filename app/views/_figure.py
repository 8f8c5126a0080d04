"""Shared look of the views: figure defaults, presenter mode, hover and ranges."""
from __future__ import annotations

import weakref

from bokeh.models import (AllIndices, AllLabels, BasicTicker, BasicTickFormatter, DataRange1d,
                          GlyphRenderer, Grid, LinearScale, PanTool, ResetTool, Selection,
                          UnionRenderers, WheelZoomTool)
from bokeh.plotting import figure

#: Tool sets by kind of view (each tool is a model, box zoom four; ``share_helpers``
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


def make_figure(name: str, title: str, x_label: str, y_label: str, **kw):
    """A figure that fills its cell of the page grid (the page sizes the cells). Its
    toolbar sits inside the frame and shows while the pointer is on the figure, so it
    takes no room from the data."""
    kw.pop("height", None)
    fig = figure(name=name, title=title, x_axis_label=x_label, y_axis_label=y_label,
                 sizing_mode="stretch_both", min_width=120, min_height=80,
                 tools=kw.pop("tools", POINTS_TOOLS),
                 toolbar_location=kw.pop("toolbar_location", "right"), toolbar_inner=True,
                 output_backend="canvas", **kw)
    for axis in (fig.xaxis, fig.yaxis):
        axis.axis_label_text_font_style = "normal"
    fig.toolbar.logo = None
    fig.toolbar.autohide = True
    # horizontal grid lines only: the vertical ones are a model each and read little
    fig.center = [c for c in fig.center if not (isinstance(c, Grid) and c.dimension == 0)]
    style(fig, presenter=False)
    return fig


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


def share_helpers(figures) -> None:
    """Fewer models per page: every axis, grid and renderer of a figure gets its own
    instance of a few helper models that hold no state (scales, tick placement and
    labels, the selection policy, the "all rows" filter), and every renderer a glyph for
    non-selected and muted rows that no view uses (no selection tools, no legend).
    Share one instance of each among the session's figures and drop the unused glyphs
    (about 50 models of a page), and one horizontal grid among the figures. The same goes for the sources' selection (no view
    selects: no tap or box-select tool) and for the pan, wheel zoom and reset tools
    (BokehJS makes a tool's view per plot; a shared tool only shares its on/off state).
    Models cannot be shared between documents, so this runs once per session."""
    ticker, formatter, labels = BasicTicker(), BasicTickFormatter(), AllLabels()
    policy, rows, scale, selection = UnionRenderers(), AllIndices(), LinearScale(), Selection()
    tools: dict = {}
    grid_lines: dict = {}
    for fig in figures:
        fig.toolbar.tools = [_shared_tool(tools, t) for t in fig.toolbar.tools]
        # BokehJS clones a figure's scale models before setting their ranges
        if type(fig.x_scale) is LinearScale and type(fig.y_scale) is LinearScale:
            fig.x_scale = fig.y_scale = scale
        for axis in fig.xaxis + fig.yaxis:
            if type(axis.ticker) is BasicTicker:
                axis.ticker = ticker
            if type(axis.formatter) is BasicTickFormatter:
                axis.formatter = formatter
            axis.major_label_policy = labels
        # the horizontal grid lines: one Grid placed by the shared ticker (a Grid that
        # names no axis reads its ticks from its ticker and its range from each plot)
        fig.center = [grid if not _plain_grid(grid) else
                      grid_lines.setdefault("y", Grid(dimension=1, ticker=ticker))
                      for grid in fig.center]   # (fig.ygrid and fig.select walk the graph)
        for r in (r for r in fig.renderers if isinstance(r, GlyphRenderer)):
            r.nonselection_glyph = None
            r.muted_glyph = None
            r.data_source.selection_policy = policy
            # (``selected`` is read-only once built; set_from_json is how BokehJS sets it)
            r.data_source.set_from_json("selected", selection)
            r.view.filter = rows


def _plain_grid(grid) -> bool:
    """A horizontal grid as ``make_figure`` leaves it: on a y axis with the basic ticker,
    styled as Bokeh's default."""
    return (isinstance(grid, Grid) and grid.dimension == 1 and grid.axis is not None
            and type(grid.axis.ticker) is BasicTicker
            and set(grid.properties_with_values(include_defaults=False)) <= {"dimension", "axis", "ticker"})


def _shared_tool(shared: dict, tool):
    """One instance of each stateless navigation tool (by type and dimensions)."""
    if type(tool) not in (PanTool, WheelZoomTool, ResetTool):
        return tool
    key = (type(tool), getattr(tool, "dimensions", None))
    return shared.setdefault(key, tool)
