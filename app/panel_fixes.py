"""Every workaround of a Panel behaviour the app depends on, for Panel ``PANEL_VERSION``.

Each one names the upstream behaviour it works around. They reach into Panel's private
parts, so they hold for one version only: ``check_version()`` (run by
tests/app/test_panel_fixes.py) fails loudly when the installed Panel is another one;
re-check each workaround against the new version before moving the pin.
"""
from __future__ import annotations

import panel as pn

#: The Panel release these workarounds were written for and checked against.
PANEL_VERSION = "1.9.4"


class PanelVersionError(RuntimeError):
    pass


def check_version(installed: str | None = None) -> None:
    """Raise if the installed Panel is not the one the workarounds were written for."""
    installed = installed or pn.__version__
    if installed != PANEL_VERSION:
        raise PanelVersionError(
            f"app/panel_fixes.py was written for Panel {PANEL_VERSION}, found {installed}: "
            "check every workaround in it against the new version, then update "
            "PANEL_VERSION")


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



# -- a Column laid out as a CSS grid (Panel 1.9.4) ----------------------------------------

#: Stylesheet for a ``pn.Column`` displayed as a CSS grid. Upstream: Panel 1.9.4 renders
#: a ``div.scroll-button`` (for ``scroll_button_threshold``) as the last child of every
#: Column's shadow root; in a grid it is one more grid item and takes a row of its own.
GRID_COLUMN_CSS = ".scroll-button { display: none !important; }"
