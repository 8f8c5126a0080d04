"""Serve with ``panel serve app/app.py`` (page /app)."""
import sys
from pathlib import Path

import panel as pn

# `panel serve` puts this file's folder first on sys.path, where `import app` would find
# this very file; the `app` package is the folder itself, one level up.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from app import serving  # noqa: E402
from app.explorer import Explorer  # noqa: E402


def create_app() -> Explorer:
    """A new, independent session: settings from the URL, its own views and workers."""
    # a dropped websocket reconnects to the same server session (kept for
    # --unused-session-lifetime): settings and views survive a Wi-Fi hiccup
    pn.extension(notifications=False, reconnect=True)
    serving.install()
    return Explorer(args=pn.state.session_args)


if pn.state.served:
    create_app().servable(title="Impact Explorer")
