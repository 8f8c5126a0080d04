"""``panel serve --setup`` script for test_first_page.py: the first scene of the process
finishes just after the page has pulled its document (while the page renders, before
its "document ready"), the interleaving a slow first scene produces by chance.

The kernels are compiled (or loaded) here first, so that the held scene takes
milliseconds once released, well inside the page's render time."""
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from bokeh.server.session import ServerSession  # noqa: E402

import impactlib as il  # noqa: E402
from app import compute  # noqa: E402

il.warmup()

_pulled = threading.Event()
_first = threading.Lock()
_handle_pull = ServerSession._handle_pull
_build_scene = compute.build_scene


def _handle_pull_and_tell(self, message, connection):
    reply = _handle_pull(self, message, connection)
    _pulled.set()
    return reply


def _build_scene_after_pull(run):
    if _first.acquire(blocking=False):        # the first scene of the process only
        _pulled.wait(30)
        time.sleep(0.1)                        # the reply is on its way to the page
    return _build_scene(run)


ServerSession._handle_pull = _handle_pull_and_tell
compute.build_scene = _build_scene_after_pull
