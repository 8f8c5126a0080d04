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
