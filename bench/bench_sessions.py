"""What one new session costs the server, in process: CPU time and Bokeh models.

A session here is what the server does for a new page at the paper defaults: build the
session (``Explorer``), its Bokeh document, serialise it as for the page's pull, and
compute the first scene and the first diagram until all five views hold data (the
diagram complete), then tear it down. Sessions are built one after another; the first
one (cold caches: JIT, scene and diagram caches) is reported apart from the next N,
which follow one warm-up session. CPU is the process's (``time.process_time``: all
threads, so the diagram worker's share is included); wall time is reported as well.

    .venv/bin/python bench/bench_sessions.py [--sessions 10] [--json FILE] [--profile]
                                             [--compare-fixes]

The served process's workarounds (``app.serving.install``, including
``bokeh_properties.lighter_properties``) are installed as in a server; ``--compare-fixes``
also alternates sessions with Bokeh's property functions as shipped and reports both.

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


#: Where a session's CPU goes, in the order it is spent (``process_time`` between marks;
#: the diagram worker's thread counts in the phase during which it runs).
PHASES = ("session (Explorer: settings, widgets, first scene)",
          "page (Panel layout to Bokeh models)",
          "document serialised for the pull",
          "until five views and a complete diagram",
          "teardown")

#: Packages a profile's own time is summed by.
PACKAGES = ("impactlib", "app", "panel", "param", "bokeh", "numpy", "json", "tornado")


def one_session(prof=None) -> dict:
    import panel as pn
    from bokeh.document import Document

    from app import serving
    from app.explorer import Explorer

    if prof is not None:
        prof.enable()
    cpu, wall = time.process_time(), time.perf_counter()
    marks = [cpu]
    with serving.building():          # as app/app.py builds a served session
        e = Explorer(args={})
        marks.append(time.process_time())
        doc = Document()
        doc.add_root(pn.panel(e).get_root(doc))
    marks.append(time.process_time())
    payload = len(json.dumps(doc.to_json(), default=str))
    marks.append(time.process_time())
    assert e.diagram.job.done.wait(120), "diagram did not finish"
    empty = [v for v, c in VIEWS.items() if len(getattr(e, v).source.data[c]) == 0]
    assert not empty, empty
    models = len(doc.models)
    marks.append(time.process_time())
    e.release_links()
    doc.clear()
    del e, doc
    marks.append(time.process_time())
    if prof is not None:
        prof.disable()
    out = {"cpu_ms": 1e3 * (marks[-1] - cpu),
           "wall_ms": 1e3 * (time.perf_counter() - wall), "models": models,
           "json_kb": payload / 1024,
           "phases_ms": {k: 1e3 * (b - a) for k, a, b in zip(PHASES, marks, marks[1:])}}
    gc.collect()         # outside the timing: a server collects now and then, not per page
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sessions", type=int, default=10)
    ap.add_argument("--json", type=Path)
    ap.add_argument("--compare-fixes", action="store_true",
                    help="also alternate sessions with and without lighter_properties")
    ap.add_argument("--profile", action="store_true",
                    help="also profile the N sessions (cProfile, own time summed by package)")
    args = ap.parse_args(argv)
    import panel as pn

    from app import bokeh_properties, serving

    pn.extension(notifications=False)
    serving.install()
    first = one_session()
    one_session()                                   # warm-up
    runs = [one_session() for _ in range(args.sessions)]
    phases = {k: statistics.median(r["phases_ms"][k] for r in runs) for k in PHASES}
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
    print("median CPU by phase:")
    for k, v in phases.items():
        print(f"  {v:6.0f} ms  {k}")
    res["phases_ms"] = phases
    if args.compare_fixes:
        res["fixes"] = compare_fixes(args.sessions)
        bokeh_properties.lighter_properties(True)
    if args.profile:
        res["profile_share"] = profile(args.sessions)
    if args.json:
        args.json.write_text(json.dumps(res, indent=1))
    return 0


def compare_fixes(n: int) -> dict:
    """CPU per session with Bokeh's property functions as shipped and with
    ``bokeh_properties.lighter_properties``, alternated (``n`` sessions each)."""
    from app import bokeh_properties

    cpu = {"as shipped": [], "lighter_properties": []}
    for i in range(2 * n):
        name = list(cpu)[i % 2]
        bokeh_properties.lighter_properties(name != "as shipped")
        cpu[name].append(one_session()["cpu_ms"])
    med = {k: statistics.median(v) for k, v in cpu.items()}
    print(f"alternated, {n} sessions each: CPU median as shipped {med['as shipped']:.0f} ms, "
          f"with lighter_properties {med['lighter_properties']:.0f} ms "
          f"(ratio {med['lighter_properties'] / med['as shipped']:.2f})")
    return med


def profile(n: int) -> dict:
    """Own CPU time of the calling thread over ``n`` sessions, summed by package (the diagram
    worker's threads are not seen by cProfile; the phase table above includes them)."""
    import cProfile
    import pstats

    prof = cProfile.Profile(time.thread_time)
    for _ in range(n):
        one_session(prof)
    stats = pstats.Stats(prof).stats
    total = sum(v[2] for v in stats.values())

    def package(key) -> str:
        return next((k for k in PACKAGES if f"/{k}/" in key[0]), "other")

    by = dict.fromkeys(PACKAGES + ("other",), 0.0)
    for key, (_, _, own, _, callers) in stats.items():
        if key[0] == "~" and callers:          # a builtin: charged to whoever called it
            calls = sum(c[2] for c in callers.values()) or 1.0
            for caller, c in callers.items():
                by[package(caller)] += own * c[2] / calls
        else:
            by[package(key)] += own
    print(f"profile of {n} sessions, caller's thread ({1e3 * total / n:.0f} ms per session "
          "under the profiler), own CPU by package (builtins charged to their callers):")
    for k, v in sorted(by.items(), key=lambda kv: -kv[1]):
        print(f"  {100 * v / total:5.1f} %  {k}")
    top = sorted(stats.items(), key=lambda kv: -kv[1][2])[:12]
    print("largest own times:")
    for (path, line, fn), v in top:
        print(f"  {1e3 * v[2] / n:6.1f} ms/session  {fn}  ({Path(path).name}:{line}, {v[0] // n} calls)")
    return {k: v / total for k, v in by.items()}


if __name__ == "__main__":
    raise SystemExit(main())
