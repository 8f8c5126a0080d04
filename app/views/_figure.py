"""Shared look of the views: figure defaults, presenter mode, hover and ranges."""
from __future__ import annotations

import weakref

from bokeh.models import (AllIndices, AllLabels, BasicTicker, BasicTickFormatter, DataRange1d,
                          GlyphRenderer, LinearScale, UnionRenderers)
from bokeh.plotting import figure

#: Tool sets by kind of view (each tool is a model in every page; box zoom is four).
TIME_SERIES_TOOLS = "xpan,xwheel_zoom,reset"
CURVE_TOOLS = "pan,wheel_zoom,reset"
POINTS_TOOLS = "pan,wheel_zoom,box_zoom,reset"
LINE = "#1f5fa8"
IMPACT = "#d1495b"
WALL = "#444444"
STICK = "#f2b134"

#: (tick labels, axis labels, title) font sizes, normal and presenter mode.
FONTS = {False: ("12px", "13px", "14px"), True: ("18px", "20px", "22px")}
#: Presenter mode multiplies line widths and marker sizes by these.
LINE_SCALE, SIZE_SCALE = 2.0, 1.6
#: Line widths and marker sizes of each figure's glyphs as built (presenter mode scales
#: these, so toggling it twice gives back the same figure).
_BASE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def make_figure(name: str, title: str, x_label: str, y_label: str, **kw):
    """A figure that fills its cell of the page grid (the page sizes the cells)."""
    kw.pop("height", None)
    fig = figure(name=name, title=title, x_axis_label=x_label, y_axis_label=y_label,
                 sizing_mode="stretch_both", min_width=120, min_height=80,
                 tools=kw.pop("tools", POINTS_TOOLS),
                 toolbar_location=kw.pop("toolbar_location", "right"),
                 output_backend="canvas", **kw)
    for axis in (fig.xaxis, fig.yaxis):
        axis.axis_label_text_font_style = "normal"
    fig.toolbar.logo = None
    style(fig, presenter=False)
    return fig


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
    (about 50 models of a page). Models cannot be shared between documents, so this
    runs once per session."""
    ticker, formatter, labels = BasicTicker(), BasicTickFormatter(), AllLabels()
    policy, rows, scale = UnionRenderers(), AllIndices(), LinearScale()
    for fig in figures:
        # BokehJS clones a figure's scale models before setting their ranges
        if type(fig.x_scale) is LinearScale and type(fig.y_scale) is LinearScale:
            fig.x_scale = fig.y_scale = scale
        for axis in fig.xaxis + fig.yaxis:
            if type(axis.ticker) is BasicTicker:
                axis.ticker = ticker
            if type(axis.formatter) is BasicTickFormatter:
                axis.formatter = formatter
            axis.major_label_policy = labels
        for grid in fig.center:         # (fig.xgrid and fig.select walk the whole graph)
            if type(getattr(grid, "ticker", None)) is BasicTicker:
                grid.ticker = ticker
        for r in (r for r in fig.renderers if isinstance(r, GlyphRenderer)):
            r.nonselection_glyph = None
            r.muted_glyph = None
            r.data_source.selection_policy = policy
            r.view.filter = rows
