"""The Panel and Bokeh workarounds hold for one version of each: fail loudly when it
changes."""
import bokeh
import panel as pn
import pytest

from app import panel_fixes


def test_installed_panel_is_the_one_the_workarounds_were_written_for():
    panel_fixes.check_version()          # raises PanelVersionError naming both versions
    assert pn.__version__ == panel_fixes.PANEL_VERSION
    assert bokeh.__version__ == panel_fixes.BOKEH_VERSION


def test_a_different_panel_fails_loudly():
    with pytest.raises(panel_fixes.PanelVersionError, match="1.9.4.*1.10.0"):
        panel_fixes.check_version("1.10.0")
    with pytest.raises(panel_fixes.PanelVersionError, match="Bokeh 3.9.2.*3.10.0"):
        panel_fixes.check_version(bokeh="3.10.0")


def test_the_private_parts_the_workarounds_touch_exist():
    """What each workaround relies on, so a Panel that moved them fails here too."""
    from panel.io import document as pdoc
    from panel.links import Callback
    from panel.reactive import Syncable

    assert Syncable._debounce == 50                      # PromptFloatSlider's baseline
    for name in ("_dispatch_msgs", "_dispatch_write_task", "_WRITE_BLOCK", "_WRITE_MSGS"):
        assert hasattr(pdoc, name), name                 # deliver_stranded_writes
    assert hasattr(pdoc, "_run_write_futures") and hasattr(pdoc, "_WRITE_FUTURES")
    assert hasattr(Callback, "registry")                 # release_links
    import panel as pn
    assert "scroll_button_threshold" in pn.Column.param      # GRID_COLUMN_CSS


def test_the_bokehjs_parts_the_reconnect_fix_touches_exist():
    """RECONNECT_JS patches BokehJS's ClientConnection by name; a BokehJS that renamed
    them (or fixed the repull) fails here."""
    from pathlib import Path

    bokehjs = (Path(bokeh.__file__).parent / "server/static/js/bokeh.min.js").read_text()
    for name in ("_on_open(", "_repull_session_doc(", "_pull_doc_json(", "_notified_idle",
                 "destructively_move(", "this._receiver.consume("):
        assert name in bokehjs, name
    # the upstream bug itself: the repull replaces the document without its buffers
    assert "this.session.document.replace_with_json(n)" in bokehjs
    for name in ("client/connection", "protocol/receiver", "document"):
        assert f'"{name}"' in panel_fixes.RECONNECT_JS


def test_a_socket_the_keep_alive_let_go_closes_quietly():
    """The race replayed with Bokeh's own objects: the keep-alive's ``client_lost``
    detaches the session, then tornado calls ``on_close``. Upstream raises; the
    workaround returns, and a live connection still goes through upstream."""
    from types import SimpleNamespace

    from bokeh.server.connection import ServerConnection
    from bokeh.server.views.ws import WSHandler

    panel_fixes.tolerate_lost_by_keep_alive()
    upstream = WSHandler.on_close.__wrapped__

    def handler():
        notified, lost = [], []
        session = SimpleNamespace(subscribe=lambda c: None, unsubscribe=lambda c: None,
                                  notify_connection_lost=lambda: notified.append(1))
        conn = ServerConnection(None, None, None, session)
        app = SimpleNamespace(client_lost=lambda c: (lost.append(c), c.detach_session()))
        return SimpleNamespace(connection=conn, close_code=None, close_reason=None,
                               application=app), notified, lost

    gone, _, _ = handler()
    gone.application.client_lost(gone.connection)       # what the failed ping does
    with pytest.raises(AssertionError):
        upstream(gone)                                   # the upstream bug
    WSHandler.on_close(gone)                             # quiet

    live, notified, lost = handler()
    WSHandler.on_close(live)
    assert notified == [1] and lost == [live.connection]


def test_an_update_for_a_page_that_left_is_not_a_warning(caplog):
    """Panel's own write loop, run on futures that fail as tornado's do when the browser
    has closed the socket: upstream warns, the workaround logs at info; any other write
    error still warns."""
    import asyncio
    import logging

    from bokeh.document import Document
    from panel.io import document as pdoc
    from tornado.websocket import WebSocketClosedError

    panel_fixes.quiet_writes_to_a_left_page()
    upstream = pdoc._run_write_futures.__wrapped__

    async def failing(exc):
        raise exc

    def run(write_loop, exc):
        doc = Document()
        caplog.clear()

        async def main():
            pdoc._WRITE_FUTURES[doc] = [asyncio.ensure_future(failing(exc))]
            await write_loop(doc)
        with caplog.at_level(logging.INFO, logger=pdoc.__name__):
            asyncio.run(main())
        return [r.levelno for r in caplog.records if r.name == pdoc.__name__]

    assert run(upstream, WebSocketClosedError()) == [logging.WARNING]   # the upstream line
    assert run(pdoc._run_write_futures, WebSocketClosedError()) == [logging.INFO]
    assert run(pdoc._run_write_futures, OSError("disk")) == [logging.WARNING]


def test_the_viewport_template_adds_the_tag_panels_page_lacks():
    """Panel's page template has no viewport meta tag (the upstream gap); rendered as
    Panel renders a document's string template, ours has exactly one, in the head."""
    from panel.io.resources import BASE_TEMPLATE
    from panel.io.server import html_page_for_render_items
    from bokeh.embed.bundle import Bundle

    tag = 'name="viewport" content="width=device-width, initial-scale=1"'
    bundle = Bundle(js_files=[], js_raw=[], css_files=[], css_raw=[], hashes={})
    page = {t: html_page_for_render_items(bundle, {}, [], "t", template=t)
            for t in (BASE_TEMPLATE, panel_fixes.VIEWPORT_TEMPLATE)}
    assert "viewport" not in page[BASE_TEMPLATE]
    ours = page[panel_fixes.VIEWPORT_TEMPLATE]
    assert ours.count(tag) == 1 and ours.index(tag) < ours.index("</head>")


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
            panel_fixes.lighter_properties(True)
            ours = m.properties_with_values(include_defaults=False)
            defaults = {c: dict(c._overridden_defaults()) for c in classes}
            panel_fixes.lighter_properties(False)
            theirs = m.properties_with_values(include_defaults=False)
            assert ours.keys() == theirs.keys(), type(m).__name__
            for k, v in ours.items():
                assert v is theirs[k] or repr(v) == repr(theirs[k]), (type(m).__name__, k)
        for c in classes:
            assert defaults[c] == c._overridden_defaults(), c
    finally:
        panel_fixes.lighter_properties(False)
    assert "_overridden_defaults" in vars(HasProps)


def test_the_bokeh_parts_lighter_properties_replaces_are_as_written_for():
    """The upstream functions the shortcuts replace still read every value before
    choosing, and merge the MRO on each call; a Bokeh that changed them fails here."""
    import inspect

    from bokeh.core.has_props import HasProps

    panel_fixes.lighter_properties(False)
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

    panel_fixes.lighter_properties(on)
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
        panel_fixes.lighter_properties(False)
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
            panel_fixes.lighter_properties(on)
            made.clear()
            axis = LinearAxis(ticker=ticker)
            assert axis.ticker is ticker
            if on:
                assert made == ["LinearAxis", "BasicTickFormatter", "AllLabels"]
            else:
                assert made.count("BasicTicker") == 1     # made and dropped upstream
    finally:
        Model.__init__ = original
        panel_fixes.lighter_properties(False)


def test_empty_container_defaults_are_made_when_read_not_with_the_model():
    """Upstream makes every list, dict and set default of a new model, and its document
    walk reads each one again; with the shortcut, a model on a page holds only those that
    were set or read, and a default read later is still the same, stable object."""
    from bokeh.document import Document
    from bokeh.models import ColumnDataSource, GlyphRenderer, Scatter

    for on in (False, True):
        panel_fixes.lighter_properties(on)
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
            panel_fixes.lighter_properties(False)
