"""What one new session costs the server, in process: CPU time and Bokeh models.

A session here is what the server does for a new page at the paper defaults: build the
session (``Explorer``), its Bokeh document, serialise it as for the page's pull, and
compute the first scene and the first diagram until all five views hold data (the
diagram complete), then tear it down. Sessions are built one after another; the first
one (cold caches: JIT, scene and diagram caches) is reported apart from the next N,
which follow one warm-up session. CPU is the process's (``time.process_time``: all
threads, so the diagram worker's share is included); wall time is reported as well.

    .venv/bin/python bench/bench_sessions.py [--sessions 10] [--json FILE]

Run it on a quiet machine; medians are reported. Without a server the scene is
computed in the caller's thread and results are applied at once (no websocket), so
this is the server's share of a session, not the client's.
"""
from __future__ import annotations

import argparse
import gc
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

VIEWS = {"displacement": "x", "phase": "x", "impact_map": "v", "poincare": "x",
         "bifurcation": "omega"}


def one_session() -> dict:
    import panel as pn
    from bokeh.document import Document

    from app.explorer import Explorer

    cpu, wall = time.process_time(), time.perf_counter()
    e = Explorer(args={})
    doc = Document()
    doc.add_root(pn.panel(e).get_root(doc))
    payload = len(json.dumps(doc.to_json(), default=str))
    assert e.runner.done.wait(120), "diagram did not finish"
    empty = [v for v, c in VIEWS.items() if len(getattr(e, v).source.data[c]) == 0]
    assert not empty, empty
    models = len(doc.models)
    e.release_links()
    doc.clear()
    del e, doc
    out = {"cpu_ms": 1e3 * (time.process_time() - cpu),
           "wall_ms": 1e3 * (time.perf_counter() - wall), "models": models,
           "json_kb": payload / 1024}
    gc.collect()         # outside the timing: a server collects now and then, not per page
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sessions", type=int, default=10)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    import panel as pn

    pn.extension(notifications=False)
    first = one_session()
    one_session()                                   # warm-up
    runs = [one_session() for _ in range(args.sessions)]
    res = {"first": first, "sessions": args.sessions,
           "cpu_ms_median": statistics.median(r["cpu_ms"] for r in runs),
           "cpu_ms_max": max(r["cpu_ms"] for r in runs),
           "wall_ms_median": statistics.median(r["wall_ms"] for r in runs),
           "models": runs[-1]["models"], "json_kb": runs[-1]["json_kb"]}
    print(f"first session: {first['cpu_ms']:.0f} ms CPU, {first['wall_ms']:.0f} ms wall, "
          f"{first['models']} models")
    print(f"next {args.sessions} (after one warm-up): CPU median {res['cpu_ms_median']:.0f} ms "
          f"(max {res['cpu_ms_max']:.0f}), wall median {res['wall_ms_median']:.0f} ms, "
          f"{res['models']} Bokeh models, document {res['json_kb']:.0f} kB")
    if args.json:
        args.json.write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
