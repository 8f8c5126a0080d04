"""Shared look of the five views."""
from __future__ import annotations

from bokeh.plotting import figure

HEIGHT = 300
TOOLS = "pan,wheel_zoom,box_zoom,reset,save"
LINE = "#1f5fa8"
IMPACT = "#d1495b"
WALL = "#444444"


def make_figure(name: str, title: str, x_label: str, y_label: str, **kw):
    """A figure sized to stretch across its column, with readable labels."""
    fig = figure(name=name, title=title, x_axis_label=x_label, y_axis_label=y_label,
                 height=kw.pop("height", HEIGHT), sizing_mode="stretch_width",
                 min_width=280, tools=kw.pop("tools", TOOLS), toolbar_location="right",
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
