"""The shortcuts of app.bokeh_properties give Bokeh's own values and page, and the Bokeh
parts they replace are as written for."""
import panel as pn
import pytest

from app import bokeh_properties


def test_lighter_properties_give_bokehs_own_values_for_every_model_of_a_page():
    """Both shortcuts of ``lighter_properties`` against Bokeh's own functions, model by
    model over a session's whole page (the shortcut's answer taken first, so a default it
    failed to create would be missing from Bokeh's answer after it)."""
    from bokeh.core.has_props import HasProps
    from bokeh.document import Document

    from app.explorer import Explorer

    doc = Document()
    doc.add_root(pn.panel(Explorer(args={})).get_root(doc))
    classes = {type(m) for m in doc.models}
    try:
        for m in doc.models:
            bokeh_properties.lighter_properties(True)
            ours = m.properties_with_values(include_defaults=False)
            defaults = {c: dict(c._overridden_defaults()) for c in classes}
            bokeh_properties.lighter_properties(False)
            theirs = m.properties_with_values(include_defaults=False)
            assert ours.keys() == theirs.keys(), type(m).__name__
            for k, v in ours.items():
                assert v is theirs[k] or repr(v) == repr(theirs[k]), (type(m).__name__, k)
        for c in classes:
            assert defaults[c] == c._overridden_defaults(), c
    finally:
        bokeh_properties.lighter_properties(False)
    assert "_overridden_defaults" in vars(HasProps)


def test_the_bokeh_parts_lighter_properties_replaces_are_as_written_for():
    """The upstream functions the shortcuts replace still read every value before
    choosing, and merge the MRO on each call; a Bokeh that changed them fails here."""
    import inspect

    from bokeh.core.has_props import HasProps

    bokeh_properties.lighter_properties(False)
    query = inspect.getsource(HasProps.query_properties_with_values)
    assert query.index("descriptor.get_value(self)") < query.index("if key not in selected_keys")
    assert "for c in reversed(cls.__mro__)" in inspect.getsource(HasProps._overridden_defaults)
    from bokeh.core.property.descriptors import PropertyDescriptor

    init = inspect.getsource(HasProps.__init__)
    assert "setattr(self, name, value)" in init and "desc.has_unstable_default(self)" in init
    assert "old = self._get(obj)" in inspect.getsource(PropertyDescriptor.__set__)
    assert "getattr(self, '__themed_values__', None)" in inspect.getsource(HasProps.themed_values)
    from bokeh.model import util

    visit = inspect.getsource(util.visit_immediate_value_references)
    assert "for attr in value.properties_with_refs():" in visit and "getattr(value, attr)" in visit


def _page_json(on: bool, validated: bool = True, args: dict | None = None) -> str:
    """A session's whole page at the defaults, serialised as for the browser's pull,
    built with ``lighter_properties(on)``; ids, Panel's numbered names and object
    addresses (which count what was made, not what was kept) replaced by their order."""
    import json
    import re

    from bokeh.document import Document

    from app.explorer import Explorer

    from bokeh.core.property.validation import validate

    from app import serving

    bokeh_properties.lighter_properties(on)
    try:
        with (validate(True) if validated else serving.building()):
            e = Explorer(args=args or {})
            doc = Document()
            doc.add_root(pn.panel(e).get_root(doc))
        for job in (e.diagram.job, *e.compare.jobs, e.research.job, e.research.boundary_job):
            assert job.done.wait(120), job.name
        text = json.dumps(doc.to_json(), sort_keys=True, default=str)
        e.release_links()
    finally:
        bokeh_properties.lighter_properties(False)
    text = re.sub(r"<memory at 0x[0-9a-f]+>", "buffer", text)
    text = re.sub(r"\bin \d+(\.\d+)? m?s\b", "in T", text)      # run times shown
    text = re.sub(r"\b1[0-9]{14}\b", "address", text)
    text = re.sub(r"([A-Za-z]+)\d{5}(?=['\"])", r"\1N", text)
    ids: dict = {}
    return re.sub(r"(?<=['\"])p\d+(?=['\"])",
                  lambda m: ids.setdefault(m.group(0), f"id{len(ids)}"), text)


def test_lighter_properties_build_the_same_page_as_bokeh():
    """Models built without their throwaway defaults, and themes read without the
    exception: the page the browser pulls is Bokeh's own, model for model and value for
    value (the shortcuts fail this if they dropped a default Bokeh keeps or stored a
    value Bokeh does not)."""
    _page_json(False)                    # caches warm, so both pages hold the same data
    theirs, ours = _page_json(False), _page_json(True)
    assert ours.count("'id': ") == theirs.count("'id': ") > 150
    assert ours == theirs


@pytest.mark.parametrize("link", ["", "scene=fig4&presenter=1&mode=compare",
                                  "omega=2.62&mode=research&boundaries=1"])
def test_a_session_built_without_property_validation_is_the_validated_page(link):
    """app/app.py builds a served session inside ``serving.building()`` (Bokeh's
    property validation off): the page must come out value for value as with validation
    on (a value Bokeh would have converted on validation, or refused, differs here),
    for each mode and presenter built from a link."""
    from urllib.parse import parse_qsl

    from bokeh.core.property.bases import validation_on

    args = {k: [v.encode()] for k, v in parse_qsl(link)}
    _page_json(True, args=args)
    validated = _page_json(True, args=args)
    built = _page_json(True, validated=False, args=args)
    assert validation_on()                     # on again after the build
    assert built.count("'id': ") == validated.count("'id': ") > 150
    assert built == validated


def test_lighter_properties_make_no_throwaway_models():
    """The upstream waste itself: an axis given its ticker made a default ticker first."""
    from bokeh.model import Model
    from bokeh.models import BasicTicker, LinearAxis

    made = []
    original = Model.__init__

    def counting(self, *a, **kw):
        made.append(type(self).__name__)
        original(self, *a, **kw)

    ticker = BasicTicker()
    Model.__init__ = counting
    try:
        for on in (False, True):
            bokeh_properties.lighter_properties(on)
            made.clear()
            axis = LinearAxis(ticker=ticker)
            assert axis.ticker is ticker
            if on:
                assert made == ["LinearAxis", "BasicTickFormatter", "AllLabels"]
            else:
                assert made.count("BasicTicker") == 1     # made and dropped upstream
    finally:
        Model.__init__ = original
        bokeh_properties.lighter_properties(False)


def test_empty_container_defaults_are_made_when_read_not_with_the_model():
    """Upstream makes every list, dict and set default of a new model, and its document
    walk reads each one again; with the shortcut, a model on a page holds only those that
    were set or read, and a default read later is still the same, stable object."""
    from bokeh.document import Document
    from bokeh.models import ColumnDataSource, GlyphRenderer, Scatter

    for on in (False, True):
        bokeh_properties.lighter_properties(on)
        try:
            r = GlyphRenderer(glyph=Scatter(), data_source=ColumnDataSource())
            doc = Document()
            doc.add_root(r)
            made = set(r._unstable_default_values)
            assert ("view" in made) and (("tags" in made) is not on), made
            tags = r.tags
            assert r.tags is tags and tags == [] and "tags" in r._unstable_default_values
            changes = []
            doc.on_change(lambda event: changes.append(getattr(event, "attr", None)))
            r.tags.append("x")                     # a change of a default made late is sent
            assert r.tags == ["x"] and changes == ["tags"]
            assert doc.get_model_by_id(r.view.id) is r.view
        finally:
            bokeh_properties.lighter_properties(False)
