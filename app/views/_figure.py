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
                 min_width=280, tools=TOOLS, toolbar_location="right",
                 output_backend="canvas", **kw)
    fig.title.text_font_size = "14px"
    for axis in (fig.xaxis, fig.yaxis):
        axis.axis_label_text_font_size = "13px"
        axis.axis_label_text_font_style = "normal"
        axis.major_label_text_font_size = "12px"
    fig.toolbar.logo = None
    return fig
