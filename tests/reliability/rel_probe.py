"""``panel serve --setup`` script for the reliability tests: counts live objects on request.

The test writes ``request`` into $IMPACT_PROBE_DIR; this thread (in the server process)
runs a full garbage collection, counts the objects of a few types that make up a session
and writes ``answer.json``. Nothing runs unless asked, so it does not disturb timings.
"""
import gc
import json
import os
import threading
import time
from collections import Counter

NAMES = ("Explorer", "Settings", "Document", "ServerSession", "ColumnDataSource")
DIR = os.environ.get("IMPACT_PROBE_DIR")


def _serve_requests():
    request = os.path.join(DIR, "request")
    answer = os.path.join(DIR, "answer.json")
    while True:
        time.sleep(0.1)
        if not os.path.exists(request):
            continue
        os.remove(request)
        gc.collect()
        counts = Counter(type(o).__name__ for o in gc.get_objects())
        with open(answer + ".tmp", "w") as f:
            json.dump({n: counts.get(n, 0) for n in NAMES}, f)
        os.replace(answer + ".tmp", answer)


if DIR:
    threading.Thread(target=_serve_requests, daemon=True, name="reliability-probe").start()
