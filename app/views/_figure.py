"""Shared look of the five views."""
from __future__ import annotations

from bokeh.models import (AllIndices, AllLabels, BasicTicker, BasicTickFormatter,
                          GlyphRenderer, LinearScale, UnionRenderers)
from bokeh.plotting import figure

HEIGHT = 300
#: Tool sets by kind of view (each tool is a model in every page; box zoom is four).
TIME_SERIES_TOOLS = "xpan,xwheel_zoom,reset"
CURVE_TOOLS = "pan,wheel_zoom,reset"
POINTS_TOOLS = "pan,wheel_zoom,box_zoom,reset"
LINE = "#1f5fa8"
IMPACT = "#d1495b"
WALL = "#444444"


def make_figure(name: str, title: str, x_label: str, y_label: str, **kw):
    """A figure sized to stretch across its column, with readable labels."""
    fig = figure(name=name, title=title, x_axis_label=x_label, y_axis_label=y_label,
                 height=kw.pop("height", HEIGHT), sizing_mode="stretch_width",
                 min_width=280, tools=kw.pop("tools", POINTS_TOOLS),
                 toolbar_location=kw.pop("toolbar_location", "right"),
                 output_backend="canvas", **kw)
    fig.title.text_font_size = "14px"
    for axis in (fig.xaxis, fig.yaxis):
        axis.axis_label_text_font_size = "13px"
        axis.axis_label_text_font_style = "normal"
        axis.major_label_text_font_size = "12px"
    fig.toolbar.logo = None
    return fig


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
