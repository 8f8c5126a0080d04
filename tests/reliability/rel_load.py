"""A classroom against one served app: N concurrent sessions moving sliders.

Each session is a Bokeh client session on the real page (``bokeh.client.pull_session``,
Panel's models registered), driving the page's own widget models through the session
document, as a browser's BokehJS does, and waiting for the plots' data sources to change.
Per session, until the deadline: move the omega slider (2 moves in 3) or the r slider (1
in 3, which restarts the bifurcation diagram), wait for the displacement data to arrive,
and after an r move also for the diagram to finish; think 0.2-0.6 s; repeat.

Measured: update latency (slider change sent -> displacement data applied in the client
document), diagram latency (r change -> diagram title says complete), and the server's
resident memory (VmRSS of its process) before, during and after.

Run standalone for the full classroom figures (they go into RELIABILITY.md):

    .venv/bin/python tests/reliability/rel_load.py --sessions 24 --seconds 60 --rounds 2 --write
"""
from __future__ import annotations

import dataclasses
import json
import os
import platform
import random
import statistics
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rel_server import RESULTS, ROOT, Served, open_session, pump, slider, source  # noqa: E402

VIEWS = ("displacement", "phase", "impact_map", "poincare", "bifurcation")


@dataclasses.dataclass
class SessionLog:
    index: int
    latencies: list = dataclasses.field(default_factory=list)      # scene updates, s
    diagram: list = dataclasses.field(default_factory=list)        # diagram completions, s
    changed: set = dataclasses.field(default_factory=set)          # views seen changing
    marker_ok: bool = False
    timeouts: int = 0
    error: str = ""
    connect: float = 0.0


def _columns(doc):
    return {v: source(doc, v).data.get("x" if v not in ("impact_map", "bifurcation") else
                                       ("v" if v == "impact_map" else "omega")) for v in VIEWS}


def _diagram_title(doc) -> str:
    return doc.get_model_by_name("bifurcation_figure").title.text or ""


def drive(url: str, log: SessionLog, start: float, deadline: float, bif_n: int) -> None:
    """One student: connect, then move sliders until the deadline."""
    rng = random.Random(1000 + log.index)          # a per-session generator, not global
    session = None
    try:
        time.sleep(max(0.0, start - time.monotonic()))
        tic = time.monotonic()
        session = open_session(url, {"bif_n": str(bif_n)})
        doc = session.document
        log.connect = time.monotonic() - tic
        pump(session, lambda: "complete" in _diagram_title(doc), 120)
        omega, r = slider(doc, "omega"), slider(doc, "r")
        k = 0
        while time.monotonic() < deadline:
            before = _columns(doc)
            title = _diagram_title(doc)
            # values on the sliders' step grid (0.01), as a browser's slider sends them,
            # and never the current value (that would change nothing)
            if k % 3 == 2:
                new_r = rng.randrange(30, 96) / 100
                while abs(new_r - r.value) < 0.005:
                    new_r = rng.randrange(30, 96) / 100
                tic = time.monotonic()
                r.value = new_r
                moved = "r"
            else:
                new_omega = rng.randrange(50, 451) / 100
                while abs(new_omega - omega.value) < 0.005:
                    new_omega = rng.randrange(50, 451) / 100
                tic = time.monotonic()
                omega.value = new_omega
                moved = "omega"
            ok = pump(session, lambda: source(doc, "displacement").data.get("x")
                      is not before["displacement"], 60)
            if not ok:
                log.timeouts += 1
                log.error = log.error or (f"no scene {60} s after {moved} -> "
                                          f"{new_r if moved == 'r' else new_omega}")
                continue
            log.latencies.append(time.monotonic() - tic)
            if moved == "r":
                done = pump(session, lambda: "complete" in _diagram_title(doc)
                            and _diagram_title(doc) != title
                            and f"r = {new_r:g}" in _diagram_title(doc), 120)
                if done:
                    log.diagram.append(time.monotonic() - tic)
                else:
                    log.timeouts += 1
            else:
                pump(session, lambda: False, 0.05)     # let the other views' patches in
                marker = doc.get_model_by_name("bifurcation_marker")
                log.marker_ok = log.marker_ok or marker.location == new_omega
            after = _columns(doc)
            log.changed |= {v for v in VIEWS if after[v] is not before[v]}
            k += 1
            think = rng.uniform(0.2, 0.6)
            pump(session, lambda: False, think)
    except Exception as exc:                            # noqa: BLE001 - reported by the test
        log.error = f"{type(exc).__name__}: {exc}"
    finally:
        if session is not None:
            try:
                session.close()
            except Exception:                           # noqa: BLE001
                pass


def _settle(srv: Served, seconds: float, step: float = 0.5) -> float:
    """RSS once it stops falling (median of the last samples), waiting at most ``seconds``."""
    samples = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        samples.append(srv.rss_mb())
        if len(samples) >= 8 and max(samples[-8:]) - min(samples[-8:]) < 1.0:
            break
        time.sleep(step)
    return statistics.median(samples[-5:])


def _pct(values, q):
    values = sorted(values)
    if not values:
        return float("nan")
    i = min(len(values) - 1, max(0, int(round(q / 100 * (len(values) - 1)))))
    return values[i]


def machine() -> str:
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return (f"{os.cpu_count()} cores ({cpu}), {mem:.0f} GB RAM, {platform.system()} "
            f"{platform.release()}, Python {platform.python_version()}")


def sessions_gone(srv: Served, timeout: float = 60.0, explorers: int = 0) -> dict:
    """Live-object counts once the server has discarded every closed session and the
    app's objects of those sessions are gone (a scene job or diagram chunk still in a
    worker keeps its session for a moment), or after ``timeout`` (then it is a leak)."""
    end = time.monotonic() + timeout
    while True:
        counts = srv.live_objects()
        if (counts["ServerSession"] == 0 and counts["Explorer"] <= explorers) \
                or time.monotonic() > end:
            return counts
        time.sleep(0.5)


def _round(srv: Served, sessions: int, seconds: float, bif_n: int, stagger: float,
           explorers: int):
    """One classroom: ``sessions`` students for ``seconds`` each; RSS sampled meanwhile."""
    peak = [srv.rss_mb()]
    stop = threading.Event()

    def sample():
        while not stop.is_set():
            try:
                peak.append(srv.rss_mb())
            except Exception:                           # noqa: BLE001
                pass
            stop.wait(0.25)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    t0 = time.monotonic()
    deadline = t0 + stagger * sessions + seconds
    logs = [SessionLog(i) for i in range(sessions)]
    threads = [threading.Thread(target=drive, args=(srv.url, logs[i], t0 + stagger * i,
                                                   deadline, bif_n), daemon=True)
               for i in range(sessions)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=seconds + stagger * sessions + 300)
    wall = time.monotonic() - t0
    closed_at = time.monotonic()
    objects = sessions_gone(srv, explorers=explorers)
    after = _settle(srv, 45)
    stop.set()
    sampler.join(5)
    return {"logs": logs, "hung": sum(t.is_alive() for t in threads), "wall": wall,
            "peak": max(peak), "after": after, "objects": objects,
            "settle": time.monotonic() - closed_at}


def run(sessions: int, seconds: float, rounds: int = 2, bif_n: int = 400,
        stagger: float = 0.25) -> dict:
    """``rounds`` classrooms one after the other on one server. Memory: the baseline
    (after one warm session), the peak, RSS after each round, and the app sessions
    still alive after each round (must be none)."""
    srv = Served("load.log", extra_args=["--check-unused-sessions", "500",
                                         "--unused-session-lifetime", "1000"], probe=True)
    try:
        # warm: one session through every path once (JIT, caches, imports), then gone
        warm = SessionLog(-1)
        drive(srv.url, warm, time.monotonic(), time.monotonic() + 4.0, bif_n)
        assert not warm.error, warm.error
        offset = srv.log_offset()
        objects_before = sessions_gone(srv, explorers=0)
        baseline = _settle(srv, 30)
        done = [_round(srv, sessions, seconds, bif_n, stagger, objects_before["Explorer"])
                for _ in range(rounds)]
        logs = [lg for r in done for lg in r["logs"]]
        lat = [x for lg in logs for x in lg.latencies]
        dia = [x for lg in logs for x in lg.diagram]
        return {
            "sessions": sessions, "seconds": seconds, "rounds": rounds, "bif_n": bif_n,
            "machine": machine(), "wall": round(sum(r["wall"] for r in done), 1),
            "hung_threads": sum(r["hung"] for r in done),
            "updates": len(lat), "diagrams": len(dia),
            "latency_median_ms": round(1e3 * statistics.median(lat), 1) if lat else None,
            "latency_p95_ms": round(1e3 * _pct(lat, 95), 1) if lat else None,
            "latency_max_ms": round(1e3 * max(lat), 1) if lat else None,
            "diagram_median_s": round(statistics.median(dia), 2) if dia else None,
            "diagram_p95_s": round(_pct(dia, 95), 2) if dia else None,
            "connect_median_s": round(statistics.median(lg.connect for lg in logs), 2),
            "rss_baseline_mb": round(baseline, 1),
            "rss_peak_mb": round(max(r["peak"] for r in done), 1),
            "rss_after_mb": [round(r["after"], 1) for r in done],
            "settle_s": round(max(r["settle"] for r in done), 1),
            "objects_before": objects_before,
            "objects_after": [r["objects"] for r in done],
            "per_session": [{"i": lg.index, "updates": len(lg.latencies),
                             "diagrams": len(lg.diagram), "views": sorted(lg.changed),
                             "marker": lg.marker_ok, "timeouts": lg.timeouts,
                             "error": lg.error} for lg in logs],
            "bad_log_lines": srv.bad_log_lines(offset)[:20],
        }
    finally:
        srv.stop()


def markdown(res: dict) -> str:
    return "\n".join([
        f"- machine: {res['machine']}; server and the {res['sessions']} client sessions on "
        "the same machine (loopback), clients as Bokeh client sessions in one process",
        f"- {res['rounds']} rounds of {res['sessions']} concurrent sessions, each session "
        f"{res['seconds']:g} s (staggered start, {res['wall']:g} s in all), default diagram "
        f"of {res['bif_n']} ω values: {res['updates']} scene updates, {res['diagrams']} "
        f"diagram recomputes",
        f"- scene update latency (slider change sent → displacement data applied in the "
        f"client): median **{res['latency_median_ms']} ms**, 95th percentile "
        f"**{res['latency_p95_ms']} ms**, max {res['latency_max_ms']} ms",
        f"- diagram recompute (r change → diagram complete): median "
        f"{res['diagram_median_s']} s, 95th percentile {res['diagram_p95_s']} s; "
        f"connecting (burst of {res['sessions']} within {0.25 * res['sessions']:g} s): "
        f"median {res['connect_median_s']} s",
        f"- server memory (VmRSS): baseline **{res['rss_baseline_mb']} MB** (after one warm "
        f"session), peak **{res['rss_peak_mb']} MB**, after each round's sessions closed "
        f"**{' / '.join(f'{a} MB' for a in res['rss_after_mb'])}** (settled within "
        f"{res['settle_s']} s); app sessions still alive after each round: "
        f"{' / '.join(str(o['Explorer']) for o in res['objects_after'])}",
        f"- every session's five views updated: "
        f"{all(len(s['views']) == 5 for s in res['per_session'])}; "
        f"timeouts: {sum(s['timeouts'] for s in res['per_session'])}; "
        f"errors: {sum(bool(s['error']) for s in res['per_session'])}; "
        f"server log tracebacks: {len(res['bad_log_lines'])}",
    ])


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sessions", type=int, default=24)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--from-json", metavar="PATH",
                    help="do not run: take the figures of an earlier run's JSON")
    ap.add_argument("--write", action="store_true",
                    help="put the figures into RELIABILITY.md (between the load markers)")
    args = ap.parse_args(argv)
    if args.from_json:
        res = json.loads(Path(args.from_json).read_text())
    else:
        res = run(args.sessions, args.seconds, args.rounds)
        RESULTS.mkdir(parents=True, exist_ok=True)
        (RESULTS / f"load-{args.sessions}.json").write_text(json.dumps(res, indent=1))
    text = markdown(res)
    print(text)
    print(json.dumps({k: v for k, v in res.items() if k != "per_session"}, indent=1))
    if args.write:
        doc = ROOT / "RELIABILITY.md"
        body = doc.read_text()
        a, b = "<!-- load:start -->", "<!-- load:end -->"
        head, rest = body.split(a, 1)
        _, tail = rest.split(b, 1)
        doc.write_text(f"{head}{a}\n{text}\n{b}{tail}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
