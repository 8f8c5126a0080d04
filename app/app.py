"""Serve with ``panel serve app/app.py`` (page /app), or ``impact-explorer serve`` from an
installed package (where this folder is the package ``impact_explorer``)."""
import importlib
import sys
from pathlib import Path

import panel as pn

# `panel serve` puts this file's folder first on sys.path, where `import app` would find
# this very file; the package is the folder itself (`app` in a checkout,
# `impact_explorer` when installed), imported from one level up.
_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE.parent))
serving = importlib.import_module(f"{_HERE.name}.serving")
Explorer = importlib.import_module(f"{_HERE.name}.explorer").Explorer
panel_fixes = importlib.import_module(f"{_HERE.name}.panel_fixes")


def create_app() -> Explorer:
    """A new, independent session: settings from the URL, its own views and workers."""
    # a dropped websocket reconnects to the same server session (kept for
    # --unused-session-lifetime): settings and views survive a Wi-Fi hiccup
    # no BrowserInfo model: the app reads none of it, and a browser sends seven patches
    # to fill it in on every new page
    pn.extension(notifications=False, reconnect=True, browser_info=False)
    serving.install()
    panel_fixes.add_viewport_tag(pn.state.curdoc)
    return Explorer(args=pn.state.session_args)


if pn.state.served:
    with serving.building():
        create_app().servable(title="Impact Explorer")
