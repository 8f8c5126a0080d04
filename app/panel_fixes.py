"""Every workaround of a Panel or Bokeh behaviour the app depends on, for Panel
``PANEL_VERSION`` and Bokeh ``BOKEH_VERSION``.

Each one names the upstream behaviour it works around. They reach into private parts,
so they hold for one version only: ``check_version()`` (run by
tests/app/test_panel_fixes.py) fails loudly when the installed Panel or Bokeh is
another one; re-check each workaround against the new version before moving the pin.
The shortcuts in Bokeh's property machinery, written for the same Bokeh, are in
``app.bokeh_properties``.
"""
from __future__ import annotations

import panel as pn

#: The Panel release these workarounds were written for and checked against.
PANEL_VERSION = "1.9.4"
#: The Bokeh release the Bokeh workarounds were written for and checked against.
BOKEH_VERSION = "3.9.2"


class PanelVersionError(RuntimeError):
    pass


def check_version(installed: str | None = None, bokeh: str | None = None) -> None:
    """Raise if the installed Panel or Bokeh is not the one the workarounds were
    written for."""
    import bokeh as bk

    for name, found, pinned in (("Panel", installed or pn.__version__, PANEL_VERSION),
                                ("Bokeh", bokeh or bk.__version__, BOKEH_VERSION)):
        if found != pinned:
            raise PanelVersionError(
                f"app/panel_fixes.py was written for {name} {pinned}, found {found}: "
                "check every workaround in it against the new version, then update "
                f"{name.upper()}_VERSION")


# -- slider events (Panel 1.9.4) ----------------------------------------------------------

class PromptFloatSlider(pn.widgets.FloatSlider):
    """FloatSlider that reports moves after 10 ms instead of 50 ms.

    Panel 1.9.4: ``Syncable._debounce`` (private, 50 ms) coalesces browser events before
    callbacks run. A scene update costs a few ms, so the slider feels late; 10 ms still
    coalesces the events of one drag frame.
    """

    _debounce = 10


# -- stranded websocket writes (Panel 1.9.4) ----------------------------------------------

def deliver_stranded_writes() -> None:
    """Send model updates that Panel 1.9.4 leaves queued under load.

    Upstream (``panel.io.document``): when the websocket is busy, Panel queues the
    message in ``_WRITE_MSGS[doc]``, sets ``_WRITE_BLOCK[doc]`` and retries in a
    ``_dispatch_msgs`` task. A task that finishes writing deletes the block without
    looking at the queue; a retry task that then finds no block returns, so a message
    queued meanwhile stays there until the session's next change: the user moved a
    slider and nothing happens (seen under 24 sessions: 2 of 52 slider moves in
    Chromium; replayed step by step in tests/reliability/test_load.py). The wrapper
    sends whatever is left. Idempotent, per process.
    """
    from panel.io import document as pdoc

    if getattr(pdoc._dispatch_msgs, "_impact_explorer", False):
        return
    original = pdoc._dispatch_msgs

    async def dispatch_msgs(doc):
        if doc not in pdoc._WRITE_BLOCK and pdoc._WRITE_MSGS.get(doc):
            pdoc._WRITE_BLOCK[doc] = True          # a stranded message: send it now
        await original(doc)                         # its retries call this wrapper
        if doc not in pdoc._WRITE_BLOCK and pdoc._WRITE_MSGS.get(doc):
            pdoc._WRITE_BLOCK[doc] = True
            pdoc._dispatch_write_task(doc, dispatch_msgs, doc)

    dispatch_msgs._impact_explorer = True
    pdoc._dispatch_msgs = dispatch_msgs


# -- a page that left while an update was on its way (Panel 1.9.4) ----------------------

def quiet_writes_to_a_left_page() -> None:
    """Log an update that could not reach a page already gone at info, not warning.

    Upstream (``panel.io.document._run_write_futures``): a write to a websocket the
    browser closed (back, forward, reload or a closed tab while the server was sending)
    logs "Failed sending message as connection was closed" as a warning, although the
    page that would have shown the update is gone and nothing is lost. Other write
    errors keep their warning. Idempotent, per process.
    """
    import logging

    from panel.io import document as pdoc
    from tornado.websocket import WebSocketClosedError

    if getattr(pdoc._run_write_futures, "_impact_explorer", False):
        return
    log = logging.getLogger(pdoc.__name__)

    async def run_write_futures(doc):
        for future in pdoc._WRITE_FUTURES.pop(doc, []):
            try:
                await future
            except WebSocketClosedError:
                log.info("An update was not sent: its page had closed the connection")
            except Exception as e:
                log.warning(f"Failed sending message due to following error: {e}")

    run_write_futures._impact_explorer = True
    run_write_futures.__wrapped__ = pdoc._run_write_futures
    pdoc._run_write_futures = run_write_futures


# -- a socket lost twice (Bokeh 3.9.2) ----------------------------------------------------

def tolerate_lost_by_keep_alive() -> None:
    """Close a websocket quietly that Bokeh's keep-alive has already let go.

    Upstream (``bokeh.server.tornado.BokehTornado._keep_alive``): a ping that finds the
    socket closed calls ``client_lost``, which detaches the session from the
    connection; tornado then calls ``WSHandler.on_close``, which asks the connection
    for its session and fails ``assert self._session is not None``: a traceback in the
    log when a page closes just as the ping runs (seen under load: a page reloaded
    while its session was being created). The session was already released, so there
    is nothing left to do. Idempotent, per process.
    """
    import logging

    from bokeh.server.views.ws import WSHandler

    if getattr(WSHandler.on_close, "_impact_explorer", False):
        return
    original = WSHandler.on_close

    def on_close(self):
        if self.connection is not None and self.connection._session is None:
            logging.getLogger("bokeh.server.views.ws").info(
                "WebSocket connection closed: code=%s, reason=%r (already released)",
                self.close_code, self.close_reason)
            return
        original(self)

    on_close._impact_explorer = True
    on_close.__wrapped__ = original
    WSHandler.on_close = on_close


# -- reconnecting to the same session (BokehJS 3.9.2) -------------------------------------

#: Patches of BokehJS's ``ClientConnection``, run in the page once its document is ready.
#: 1. The receiver that assembles multi-frame messages outlives a lost connection: a
#:    link that drops in the middle of a message leaves it half-way, and every message
#:    of the new connection is read out of phase ("First message was not an ACK", "No
#:    msgid in header"). A fresh receiver per opened socket starts clean.
#: 2. A reconnect pulls the document again and calls ``replace_with_json`` without the
#:    reply's binary buffers, so any ColumnDataSource holding a numpy array fails with
#:    "buffer for id=... not found" and the reconnect is abandoned (bokeh/bokeh#15347,
#:    fixed upstream after 3.9.2). The repull below passes them. The document announced
#:    "idle" once and never again, so Panel's Location (which writes the URL only after
#:    idle) and the views' ready hooks would stay silent for the new models: the flag is
#:    reset so that idle and ``document_ready`` come again once the new views are drawn.
RECONNECT_JS = """
if (!window.__ieReconnectFix) {
  window.__ieReconnectFix = true
  const {ClientConnection} = Bokeh.require("client/connection")
  const {Receiver} = Bokeh.require("protocol/receiver")
  const {Document} = Bokeh.require("document")
  const proto = ClientConnection.prototype
  const on_open = proto._on_open
  proto._on_open = function (...args) {
    this._receiver = new Receiver()
    return on_open.apply(this, args)
  }
  const repull = proto._repull_session_doc
  proto._repull_session_doc = async function (resolve, reject) {
    if (this.session == null)
      return repull.call(this, resolve, reject)
    try {
      const {doc_json, buffers} = await this._pull_doc_json()
      const doc = this.session.document
      doc._notified_idle = false
      Document.from_json(doc_json, undefined, buffers).destructively_move(doc)
      resolve(this.session)
    } catch (e) {
      console.error("reconnect: could not pull the document again", e)
      reject(e instanceof Error ? e : `${e}`)
    }
  }
}
"""


def repair_reconnect(doc) -> None:
    """Install ``RECONNECT_JS`` in the page of ``doc`` when it is ready (see there).
    tests/browser/test_reconnect.py cuts a page's connection mid-stream and needs it."""
    from bokeh.models import CustomJS

    doc.js_on_event("document_ready", CustomJS(code=RECONNECT_JS))


# -- link registry leak (Panel 1.9.4) -----------------------------------------------------

def release_links(layout) -> None:
    """Drop the entries of the widgets under ``layout`` from Panel's link registry.

    Upstream: Panel 1.9.4 keeps every jslink/jscallback in
    ``panel.links.Callback.registry``, a WeakKeyDictionary keyed by the source widget
    whose values refer back to that key (e.g. an EditableFloatSlider links its text
    input to its slider), so the entries of a closed session never go away and keep
    the whole session alive (tests/reliability/test_load.py checks closed sessions are
    freed). Run when a session is destroyed.
    """
    from panel.links import Callback

    owned = {id(obj) for obj in layout.select()}
    for key in list(Callback.registry.keys()):
        if id(key) in owned:
            Callback.registry.pop(key, None)



# -- the page's viewport (Panel 1.9.4) ---------------------------------------------------

#: Upstream: the page template of Panel 1.9.4 (``panel/_templates/base.html``, used when
#: no Panel template is set) has no viewport meta tag, so a phone lays the page out 980 px
#: wide and zooms out. Panel's own templates carry one (``BasicTemplate.meta_viewport``);
#: a Bokeh document template given as a string is rendered by Panel as
#: ``{% extends base %}`` + the string, so this block adds the tag to that page.
VIEWPORT_TEMPLATE = """{% block preamble %}{{ super() }}
<meta name="viewport" content="width=device-width, initial-scale=1">
{% endblock %}"""


def add_viewport_tag(doc) -> None:
    """Serve the page of ``doc`` with ``VIEWPORT_TEMPLATE`` (see there)."""
    doc.template = VIEWPORT_TEMPLATE


# -- a Column laid out as a CSS grid (Panel 1.9.4) ----------------------------------------

#: Stylesheet for a ``pn.Column`` displayed as a CSS grid. Upstream: Panel 1.9.4 renders
#: a ``div.scroll-button`` (for ``scroll_button_threshold``) as the last child of every
#: Column's shadow root; in a grid it is one more grid item and takes a row of its own.
GRID_COLUMN_CSS = ".scroll-button { display: none !important; }"


# -- Back and Forward (Panel 1.9.4) -------------------------------------------------------

#: Upstream: Panel 1.9.4's ``Location`` pushes a history entry for every URL the session
#: writes but has no ``popstate`` listener, so Back changes the address bar and not the
#: page. The page is the URL's state: on Back or Forward it loads that URL again.
HISTORY_JS = """
if (!window.__ieHistoryFix) {
  window.__ieHistoryFix = true
  window.addEventListener("popstate", () => window.location.reload())
}
"""


def restore_on_history(doc) -> None:
    """Install ``HISTORY_JS`` in the page of ``doc`` when it is ready (see there)."""
    from bokeh.models import CustomJS

    doc.js_on_event("document_ready", CustomJS(code=HISTORY_JS))
