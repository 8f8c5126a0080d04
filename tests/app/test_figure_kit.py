"""The views draw with ``app.views._figure.add_glyph`` into figures of ``make_figure``:
the same glyphs and figures ``bokeh.plotting.figure`` makes, without its throwaway models.
The reference is Bokeh's own plotting API, called with the same arguments."""
import numpy as np
import pytest
from bokeh.models import (ColumnDataSource, Image, Line, LinearColorMapper, MultiLine, Quad,
                          Range1d, Scatter, VSpan, VStrip)
from bokeh.plotting import figure

from app.views._figure import Kit, add_glyph, make_figure

#: (glyph class, bokeh.plotting method, arguments): every kind of call the views make.
CASES = [
    (Scatter, "scatter", dict(x="t", y="x", size=4, color="#d1495b")),
    (Scatter, "scatter", dict(x="x", y="v", size=5, color="#1f5fa8", alpha=0.8)),
    (Scatter, "scatter", dict(x="x", y="v", size=11, color="#2a9d8f", line_color="white")),
    (Scatter, "scatter", dict(x="omega", y="y", size="size", marker="marker", color="color")),
    (Scatter, "scatter", dict(x="x", y="y", marker="circle_cross", size=14,
                              fill_color="white", fill_alpha=0.6, line_color="black",
                              line_width=2)),
    (Scatter, "scatter", dict(x="x", y="y", marker="diamond", size=8, fill_color="#333333",
                              line_color="#333333")),
    (Line, "line", dict(x="t", y="x", line_color="#1f5fa8", line_width=1.2)),
    (MultiLine, "multi_line", dict(xs="xs", ys="ys", line_color="color", line_width="width")),
    (MultiLine, "multi_line", dict(xs="xs", ys="ys", line_color="#d62728", line_dash="dashed",
                                   line_width=2.5)),
    (Quad, "quad", dict(left="left", right="right", bottom="bottom", top="top",
                        fill_color="#1f5fa8", line_color="#0b2f57", line_width=2)),
    (VStrip, "vstrip", dict(x0="start", x1="end", fill_color="#f2b134", fill_alpha=0.35,
                            line_alpha=0)),
    (VSpan, "vspan", dict(x="t", line_color="#2a9d8f", line_width=2, line_alpha=0.8)),
    (Image, "image", dict(image="image", x="x", y="y", dw="dw", dh="dh")),
]


def _values(model) -> dict:
    return {k: repr(v) for k, v in model.properties_with_values(include_defaults=True).items()}


@pytest.mark.parametrize("cls, method, kwargs", CASES)
def test_a_glyph_is_the_one_bokehs_plotting_api_makes(cls, method, kwargs):
    extra = {"color_mapper": LinearColorMapper(palette=["#000000", "#ffffff"])} \
        if cls is Image else {}
    theirs = getattr(figure(), method)(source=ColumnDataSource(), name="r", level="overlay",
                                       **kwargs, **extra)
    fig = make_figure("f", "title", "x", "y", kit=Kit())
    ours = add_glyph(fig, cls, ColumnDataSource(), name="r", level="overlay",
                     **kwargs, **extra)
    assert type(ours.glyph) is type(theirs.glyph)
    assert _values(ours.glyph) == _values(theirs.glyph)
    assert (ours.name, ours.level, ours.selection_glyph) == ("r", "overlay", "auto")
    # no glyph for non-selected or muted rows: no view selects or mutes
    assert ours.nonselection_glyph is None and ours.muted_glyph is None
    assert fig.renderers == [ours]


def test_a_figure_is_the_one_bokehs_figure_makes_with_shared_helpers():
    """The figure's own properties are figure()'s with the same arguments; axes, grid,
    scales, tools, filter and selection are the kit's, one instance per kit."""
    kit = Kit()
    ours = make_figure("a", "A title", "time", "x", kit=kit, tools="xpan,xwheel_zoom,reset",
                       x_range=Range1d(0, 1))
    other = make_figure("b", "B", "x", "v", kit=kit, tools="pan,wheel_zoom,box_zoom,reset")
    theirs = figure(name="a", title="A title", x_axis_label="time", y_axis_label="x",
                    sizing_mode="stretch_both", min_width=120, min_height=80,
                    tools="xpan,xwheel_zoom,reset", toolbar_location="right",
                    toolbar_inner=True, output_backend="canvas", x_range=Range1d(0, 1))
    skip = {"id", "x_range", "y_range", "x_scale", "y_scale", "below", "left", "center",
            "title", "toolbar", "renderers"}
    mine = {k: v for k, v in _values(ours).items() if k not in skip}
    assert mine == {k: v for k, v in _values(theirs).items() if k not in skip}
    assert ours.title.text == "A title" and ours.xaxis.axis_label == "time"
    assert [t.__class__.__name__ for t in ours.toolbar.tools] == \
        [t.__class__.__name__ for t in theirs.toolbar.tools]
    assert [t.dimensions for t in ours.toolbar.tools[:2]] == ["width", "width"]
    assert ours.x_scale is ours.y_scale is other.x_scale is kit.scale
    assert ours.center == other.center == [kit.grid]
    for axis in ours.xaxis + ours.yaxis + other.xaxis + other.yaxis:
        assert (axis.ticker, axis.formatter, axis.major_label_policy) == \
            (kit.ticker, kit.formatter, kit.labels)
    assert ours.toolbar.tools[2] is other.toolbar.tools[3]          # one reset tool
    assert ours.toolbar.tools[0] is not other.toolbar.tools[0]      # xpan is not pan
    a, b = (add_glyph(f, Line, ColumnDataSource({"x": np.zeros(2)}), x="x", y="x")
            for f in (ours, other))
    assert a.view.filter is b.view.filter is kit.rows
    assert a.data_source.selected is b.data_source.selected is kit.selection
    assert a.data_source.selection_policy is kit.policy


@pytest.mark.parametrize("mode", ["explore", "compare", "research"])
def test_each_modes_document_passes_bokehs_validation(mode):
    """The served process skips Bokeh's document validation (app.serving); the checks
    run here instead, on each mode's page: no error, and no warning but Bokeh's 'fixed
    sizing mode without width and height' about research's Panel widgets (Panel sizes
    them with CSS; the same warnings a validating server logs)."""
    import panel as pn
    from bokeh.core.validation.check import check_integrity
    from bokeh.document import Document

    from app.explorer import Explorer

    e = Explorer(args={"mode": mode})
    doc = Document()
    doc.add_root(pn.panel(e).get_root(doc))
    try:
        issues = check_integrity(doc.models)
        assert len(doc.models) > 100
        assert issues.error == [], issues.error
        odd = [w for w in issues.warning
               if not (w.name == "FIXED_SIZING_MODE" and mode == "research"
                       and w.extra.split("(")[0] in {"Checkbox", "CustomSelect", "Spinner",
                                                     "Button", "Select"})]
        assert odd == [], odd
    finally:
        e._on_session_destroyed(None)
