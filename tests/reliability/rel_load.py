"""A classroom against one served app: N concurrent sessions moving sliders.

Each session is a client of the real page (``--client``, see CLIENTS: Bokeh's Python
client by default here, the light client of rel_light_client.py by default for
``--targets``), driving the page's own widget models through its copy of the document,
as a browser's BokehJS does, and waiting for the plots' data sources to change.
Per session, until the deadline: move the omega slider (2 moves in 3) or the r slider (1
in 3, which restarts the bifurcation diagram), wait for the displacement data to arrive,
and after an r move also for the diagram to finish; think 0.2-0.6 s; repeat.

Measured: update latency (slider change sent -> displacement data applied in the client
document), diagram latency (r change -> diagram title says complete), and the server's
resident memory (VmRSS of its process) before, during and after.

Run standalone for the full classroom figures (they go into RELIABILITY.md):

    .venv/bin/python tests/reliability/rel_load.py --sessions 24 --seconds 60 --rounds 2 --write

and for the classroom targets (sequential sessions, a burst of 30, 30 active sessions;
one process, --num-procs 2 and nginx + 2 processes; RELIABILITY.md section 8):

    .venv/bin/python tests/reliability/rel_load.py --targets --write
    .venv/bin/python tests/reliability/rel_load.py --targets --url http://HOST:PORT/app \
        --server-pgid PGID          # any served page; CPU and RSS of that process group
"""
from __future__ import annotations

import dataclasses
import html
import json
import os
import platform
import random
import re
import resource
import signal
import statistics
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rel_light_client import open_light_session  # noqa: E402
from rel_server import (RESULTS, ROOT, Served, group_cpu_s, group_pids,  # noqa: E402
                        group_rss_mb, open_session, process_cpu_s, pump, slider, source)

VIEWS = ("displacement", "phase", "impact_map", "poincare", "bifurcation")

#: The load clients. "light" (rel_light_client.py): the page's HTTP GET, then Bokeh's
#: websocket protocol spoken directly, the document kept as plain data, what the page
#: sends once shown; "light-ws": the same without the page (the server makes the
#: session when the websocket opens, as for Bokeh's client); "bokeh": Bokeh's Python
#: client (``bokeh.client``, the document as Bokeh models: more CPU than the server).
CLIENTS = ("light", "light-ws", "bokeh")


class BokehClient:
    """Bokeh's client session (rel_server.open_session) behind the light session's
    interface: ``document``, ``models_at_pull``, ``wait(predicate, timeout)``, ``close()``."""

    def __init__(self, url: str, args: dict | None = None):
        self.session = open_session(url, args)
        self.document = self.session.document
        self.models_at_pull = len(self.document.models)

    def wait(self, predicate, timeout: float) -> bool:
        return pump(self.session, predicate, timeout)

    def close(self) -> None:
        self.session.close()


def open_client(kind: str, url: str, args: dict | None = None):
    """A session on the page at ``url`` through the load client ``kind`` (CLIENTS)."""
    if kind == "bokeh":
        return BokehClient(url, args)
    if kind in ("light", "light-ws"):
        return open_light_session(url, args, page=kind == "light")
    raise ValueError(f"unknown client {kind!r}; one of {', '.join(CLIENTS)}")


@dataclasses.dataclass
class SessionLog:
    index: int
    latencies: list = dataclasses.field(default_factory=list)      # scene updates, s
    diagram: list = dataclasses.field(default_factory=list)        # diagram completions, s
    changed: set = dataclasses.field(default_factory=set)          # views seen changing
    marker_ok: bool = False
    timeouts: int = 0
    lost: int = 0                  # slider moves whose scene never arrived (60 s)
    error: str = ""
    connect: float = 0.0


def _columns(doc):
    return {v: source(doc, v).data.get("x" if v not in ("impact_map", "bifurcation") else
                                       ("v" if v == "impact_map" else "omega")) for v in VIEWS}


def _diagram_title(doc) -> str:
    return doc.get_model_by_name("bifurcation_figure").title.text or ""


def _plain(text: str) -> str:
    """Text of a status model without markup (an HTML pane holds escaped HTML)."""
    return html.unescape(re.sub(r"<[^>]+>", "", html.unescape(text or ""))).strip()


def diagram_complete(doc) -> bool:
    """The diagram's completion signal: the model named ``bifurcation_status`` has a
    ``text`` that starts with "complete". An app without that model: its diagram
    figure's title says "complete"."""
    status = doc.get_model_by_name("bifurcation_status")
    if status is not None:
        return _plain(getattr(status, "text", "")).startswith("complete")
    return "complete" in _diagram_title(doc)


def five_views(doc) -> bool:
    """Every view's data source holds data."""
    for v in VIEWS:
        model = doc.get_model_by_name(v)
        data = model.data_source.data if model is not None else {}
        if not len(next(iter(data.values()), [])):
            return False
    return True


def drive(url: str, log: SessionLog, start: float, deadline: float, bif_n: int,
          together: threading.Barrier | None = None, seconds: float = 0.0,
          client: str = "bokeh") -> None:
    """One student: connect, then move sliders until the deadline. With ``together``,
    wait until every student's page is complete and move sliders for ``seconds`` from
    then on (all active at once, however long connecting took)."""
    rng = random.Random(1000 + log.index)          # a per-session generator, not global
    session = None
    try:
        time.sleep(max(0.0, start - time.monotonic()))
        tic = time.monotonic()
        session = open_client(client, url, {"bif_n": str(bif_n)})
        doc = session.document
        log.connect = time.monotonic() - tic
        session.wait(lambda: diagram_complete(doc), 120)
        omega, r = slider(doc, "omega"), slider(doc, "r")
        if together is not None:
            try:
                together.wait(600)
            except threading.BrokenBarrierError:
                pass
            deadline = time.monotonic() + seconds
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
            ok = session.wait(lambda: source(doc, "displacement").data.get("x")
                              is not before["displacement"], 60)
            if not ok:
                log.timeouts += 1
                log.lost += 1
                log.error = log.error or (f"no scene {60} s after {moved} -> "
                                          f"{new_r if moved == 'r' else new_omega}")
                continue
            log.latencies.append(time.monotonic() - tic)
            if moved == "r":
                done = session.wait(lambda: "complete" in _diagram_title(doc)
                                    and _diagram_title(doc) != title
                                    and f"r = {new_r:g}" in _diagram_title(doc), 120)
                if done:
                    log.diagram.append(time.monotonic() - tic)
                else:
                    log.timeouts += 1
            else:
                session.wait(lambda: False, 0.05)      # let the other views' patches in
                marker = doc.get_model_by_name("bifurcation_marker")
                log.marker_ok = log.marker_ok or marker.location == new_omega
            after = _columns(doc)
            log.changed |= {v for v in VIEWS if after[v] is not before[v]}
            k += 1
            think = rng.uniform(0.2, 0.6)
            session.wait(lambda: False, think)
    except Exception as exc:                            # noqa: BLE001 - reported by the test
        log.error = f"{type(exc).__name__}: {exc}"
        if together is not None:
            together.abort()                            # the others need not wait for it
    finally:
        if session is not None:
            try:
                session.close()
            except Exception:                           # noqa: BLE001
                pass


def _settle(srv: Served, seconds: float, step: float = 0.5) -> float:
    """RSS once it stops falling (median of the last samples), waiting at most ``seconds``."""
    return _settle_rss(srv.rss_mb, seconds, step)


def _settle_rss(rss, seconds: float, step: float = 0.5) -> float:
    samples = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        samples.append(rss())
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
           explorers: int | None, rss=None, settle=None, url: str | None = None,
           together: bool = False, client: str = "bokeh"):
    """One classroom: ``sessions`` students for ``seconds`` each; RSS sampled meanwhile.
    ``rss``/``settle`` measure memory (default: the server process), ``explorers`` the
    app sessions alive before (None: not counted, for servers without the probe)."""
    rss = rss or srv.rss_mb
    settle = settle or (lambda seconds: _settle(srv, seconds))
    peak = [rss()]
    stop = threading.Event()

    def sample():
        while not stop.is_set():
            try:
                peak.append(rss())
            except Exception:                           # noqa: BLE001
                pass
            stop.wait(0.25)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    t0 = time.monotonic()
    deadline = t0 + stagger * sessions + seconds
    logs = [SessionLog(i) for i in range(sessions)]
    barrier = threading.Barrier(sessions) if together else None
    threads = [threading.Thread(target=drive, args=(url or srv.url, logs[i],
                                                   t0 + stagger * i, deadline, bif_n,
                                                   barrier, seconds, client),
                                daemon=True)
               for i in range(sessions)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=seconds + stagger * sessions + (900 if together else 300))
    wall = time.monotonic() - t0
    closed_at = time.monotonic()
    objects = sessions_gone(srv, explorers=explorers) if explorers is not None else None
    after = settle(45)
    stop.set()
    sampler.join(5)
    return {"logs": logs, "hung": sum(t.is_alive() for t in threads), "wall": wall,
            "peak": max(peak), "after": after, "objects": objects,
            "settle": time.monotonic() - closed_at}


def run(sessions: int, seconds: float, rounds: int = 2, bif_n: int = 400,
        stagger: float = 0.25, client: str = "bokeh") -> dict:
    """``rounds`` classrooms one after the other on one server. Memory: the baseline
    (after one warm session), the peak, RSS after each round, and the app sessions
    still alive after each round (must be none)."""
    srv = Served("load.log", extra_args=["--check-unused-sessions", "500",
                                         "--unused-session-lifetime", "1000"], probe=True)
    try:
        # warm: one session through every path once (JIT, caches, imports), then gone
        warm = SessionLog(-1)
        drive(srv.url, warm, time.monotonic(), time.monotonic() + 4.0, bif_n, client=client)
        assert not warm.error, warm.error
        offset = srv.log_offset()
        objects_before = sessions_gone(srv, explorers=0)
        baseline = _settle(srv, 30)
        # sliders move for ``seconds`` once every page is complete: under load connecting
        # alone can take longer than a short round
        done = [_round(srv, sessions, seconds, bif_n, stagger, objects_before["Explorer"],
                       together=True, client=client)
                for _ in range(rounds)]
        logs = [lg for r in done for lg in r["logs"]]
        lat = [x for lg in logs for x in lg.latencies]
        dia = [x for lg in logs for x in lg.diagram]
        return {
            "sessions": sessions, "seconds": seconds, "rounds": rounds, "bif_n": bif_n,
            "client": client, "machine": machine(), "wall": round(sum(r["wall"] for r in done), 1),
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


# -- the measured targets of a classroom deployment ------------------------------------
#
# Three scenarios, each against any served page (started here, or --url):
#   sequential: one warm-up session, then N sessions one after another at the default
#       URL, each until its five views have data and its diagram is complete, then
#       closed and torn down by the server: server CPU per session;
#   burst: N sessions opening within 5 s: server CPU for the burst, connect -> five
#       views, all complete within 60 s, the test clients' own CPU apart;
#   active: N sessions moving sliders for S s: scene update and diagram latency, lost
#       updates, server memory before, at peak and after the sessions closed.

#: Discard a closed session after ~1 s (Bokeh's default is 15-30 s), so that the
#: server's teardown is inside the measured window.
FAST_DISCARD = ["--check-unused-sessions", "500", "--unused-session-lifetime", "1000"]
DEPLOYMENTS = {
    "single": "panel serve app/app.py (1 process)",
    "procs2": "panel serve app/app.py --num-procs 2",
    "proxy": "nginx (scripts/nginx.conf) in front of 2 panel serve processes",
}
SCENARIOS = ("sequential", "burst", "active")


class Target:
    """A served page and the process groups of its server ([]: not measured)."""

    def __init__(self, name: str, url: str, pgids=(), stop=lambda: None,
                 bad_log=lambda: []):
        self.name, self.url, self.pgids = name, url, list(pgids)
        self.stop, self.bad_log = stop, bad_log

    def cpu(self) -> float:
        return group_cpu_s(self.pgids) if self.pgids else float("nan")

    def rss(self) -> float:
        return group_rss_mb(self.pgids) if self.pgids else float("nan")

    def cpu_by_process(self) -> dict:
        return {p: process_cpu_s(p) for p in group_pids(self.pgids)}

    def idle(self, least: float = 1.6, most: float = 20.0) -> None:
        """Wait for the server to finish (sessions discarded, workers idle): at least
        ``least`` s, then until its CPU grows < 20 ms per 0.5 s."""
        time.sleep(least)
        if not self.pgids:
            return
        end = time.monotonic() + most
        before = self.cpu()
        while time.monotonic() < end:
            time.sleep(0.5)
            now = self.cpu()
            if now - before < 0.02:
                return
            before = now


def start_target(kind: str) -> Target:
    """Serve the app as deployment ``kind`` (a key of DEPLOYMENTS) on loopback ports."""
    if kind == "single":
        srv = Served("targets-single.log", extra_args=FAST_DISCARD)
        return Target(DEPLOYMENTS[kind], srv.url, [srv.proc.pid], srv.stop, srv.bad_log_lines)
    if kind == "procs2":
        srv = Served("targets-procs2.log", extra_args=[*FAST_DISCARD, "--num-procs", "2"])
        end = time.monotonic() + 60
        while len(group_pids([srv.proc.pid])) < 3 and time.monotonic() < end:
            time.sleep(0.2)
        return Target(DEPLOYMENTS[kind], srv.url, [srv.proc.pid], srv.stop, srv.bad_log_lines)
    if kind == "proxy":
        from rel_proxy import ProxiedApp

        app = ProxiedApp("targets-proxy", extra_args=FAST_DISCARD)
        return Target(DEPLOYMENTS[kind], app.url, app.pgids, app.stop, app.bad_log_lines)
    raise ValueError(f"unknown deployment {kind!r}; one of {', '.join(DEPLOYMENTS)}")


def client_cpu_s() -> float:
    """CPU seconds of this process (every test client thread), user + system."""
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


@dataclasses.dataclass
class Visit:
    """One session opened until its page is complete."""
    index: int
    start: float = float("nan")     # monotonic time the client began to connect
    connect: float = float("nan")   # s to a pulled document
    views: float = float("nan")     # s from the start to five views with data
    complete: float = float("nan")  # s from the start to the diagram complete
    models: int = 0                 # Bokeh models in the pulled document
    error: str = ""


def visit(url: str, v: Visit, start_at: float, limit: float = 60.0,
          client: str = "light") -> None:
    """Open one session (load client ``client``) at ``start_at``; wait (at most ``limit``
    s from the start) for its five views and its complete diagram; close it."""
    time.sleep(max(0.0, start_at - time.monotonic()))
    v.start = t0 = time.monotonic()
    session = None
    try:
        session = open_client(client, url)
        doc = session.document
        v.connect = time.monotonic() - t0
        v.models = session.models_at_pull
        if five_views(doc) or session.wait(lambda: five_views(doc),
                                           max(0.1, limit - (time.monotonic() - t0))):
            v.views = time.monotonic() - t0
        done = lambda: five_views(doc) and diagram_complete(doc)  # noqa: E731
        if done() or session.wait(done, max(0.1, limit - (time.monotonic() - t0))):
            v.complete = time.monotonic() - t0
        else:
            v.error = f"not complete {limit:g} s after connecting"
    except Exception as exc:                            # noqa: BLE001 - reported
        v.error = f"{type(exc).__name__}: {exc}"
    finally:
        if session is not None:
            try:
                session.close()
            except Exception:                           # noqa: BLE001
                pass


def _round_or_none(x, digits: int = 2):
    return None if x is None or x != x else round(x, digits)


def _stats(values) -> dict:
    values = [x for x in values if x == x]
    if not values:
        return {"median": None, "max": None}
    return {"median": round(statistics.median(values), 3), "max": round(max(values), 3)}


def scenario_sequential(target: Target, n: int = 10, client: str = "light") -> dict:
    """One warm-up session, then ``n`` sessions one after another; server CPU each,
    from before it connects until the server is idle again after it closed."""
    def one(i):
        v = Visit(i)
        c0 = target.cpu()
        visit(target.url, v, time.monotonic(), client=client)
        target.idle()
        return v, target.cpu() - c0

    first, first_cpu = one(-1)
    k0, c0 = client_cpu_s(), target.cpu()
    runs = [one(i) for i in range(n)]
    cpu = [c for _, c in runs]
    visits = [v for v, _ in runs]
    return {
        "sessions": n,
        "first_session_cpu_s": round(first_cpu, 3),
        "first_session_complete_s": round(first.complete, 2) if first.complete == first.complete else None,
        "cpu_per_session_s": {"median": round(statistics.median(cpu), 3),
                              "mean": round(sum(cpu) / n, 3), "max": round(max(cpu), 3)},
        "cpu_total_s": round(target.cpu() - c0, 2),
        "cpu_each_s": [round(c, 3) for c in cpu],
        "complete_s": _stats(v.complete for v in visits),
        "models": sorted({v.models for v in [first, *visits]}),
        "client_cpu_s": round(client_cpu_s() - k0, 2),
        "errors": [v.error for v in [first, *visits] if v.error],
    }


def scenario_burst(target: Target, n: int = 30, window: float = 5.0,
                   target_s: float = 60.0, limit: float = 300.0, client: str = "light") -> dict:
    """``n`` sessions opening within ``window`` s, each until complete (given up
    ``limit`` s after it began to connect); how many were complete ``target_s`` s after
    the burst began."""
    visits = [Visit(i) for i in range(n)]
    split0 = target.cpu_by_process()
    k0, c0, t0 = client_cpu_s(), target.cpu(), time.monotonic() + 0.5
    threads = [threading.Thread(target=visit, args=(target.url, visits[i],
                                                    t0 + window * i / max(1, n - 1), limit,
                                                    client),
                                daemon=True) for i in range(n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(limit + window + 120)
    wall = time.monotonic() - t0
    cpu, client = target.cpu() - c0, client_cpu_s() - k0
    target.idle()
    split = {p: round(c - split0.get(p, 0.0), 2) for p, c in target.cpu_by_process().items()}
    ends = [v.start - t0 + v.complete for v in visits if v.complete == v.complete]
    last = max(ends, default=float("nan"))
    return {
        "sessions": n, "window_s": window,
        "complete": len(ends),
        f"complete_within_{target_s:g}_s": sum(e <= target_s for e in ends),
        "all_complete_within_s": round(last, 2) if last == last else None,
        "server_cpu_s": round(cpu, 2),
        "server_cpu_with_teardown_s": round(target.cpu() - c0, 2),
        "server_cpu_by_process_s": split,
        "client_cpu_s": round(client, 2),
        "wall_s": round(wall, 1),
        "connect_s": _stats(v.connect for v in visits),
        "connect_to_five_views_s": _stats(v.views for v in visits),
        "connect_to_complete_s": _stats(v.complete for v in visits),
        # from the burst's start until the last session had its five views
        "all_five_views_within_s": _round_or_none(max(
            (v.start - t0 + v.views for v in visits if v.views == v.views), default=None)),
        "models": sorted({v.models for v in visits if v.models}),
        "errors": [v.error for v in visits if v.error],
        "hung_threads": sum(t.is_alive() for t in threads),
    }


def scenario_active(target: Target, n: int = 30, seconds: float = 60.0,
                    bif_n: int = 400, client: str = "light") -> dict:
    """``n`` sessions open within 5 s; once every page is complete, all move sliders
    for ``seconds`` s (see ``drive``)."""
    baseline = _settle_rss(target.rss, 30) if target.pgids else float("nan")
    k0, c0 = client_cpu_s(), target.cpu()
    r = _round(None, n, seconds, bif_n, stagger=5.0 / max(1, n), explorers=None,
               rss=target.rss, settle=lambda s: _settle_rss(target.rss, s) if target.pgids
               else float("nan"), url=target.url, together=True, client=client)
    logs = r["logs"]
    lat = [x for lg in logs for x in lg.latencies]
    dia = [x for lg in logs for x in lg.diagram]
    nan = lambda x: None if x != x else round(x, 1)  # noqa: E731
    return {
        "sessions": n, "seconds": seconds, "bif_n": bif_n,
        "updates": len(lat), "diagrams": len(dia),
        "lost_updates": sum(lg.lost for lg in logs),
        "timeouts": sum(lg.timeouts for lg in logs),
        "scene_ms": {"median": round(1e3 * statistics.median(lat), 1) if lat else None,
                     "p95": round(1e3 * _pct(lat, 95), 1) if lat else None,
                     "max": round(1e3 * max(lat), 1) if lat else None},
        "diagram_s": {"median": round(statistics.median(dia), 2) if dia else None,
                      "p95": round(_pct(dia, 95), 2) if dia else None},
        "connect_s": _stats(lg.connect for lg in logs),
        "rss_mb": {"baseline": nan(baseline), "peak": nan(r["peak"]), "after": nan(r["after"])},
        "server_cpu_s": round(target.cpu() - c0, 1),
        "client_cpu_s": round(client_cpu_s() - k0, 1),
        "views_all_updated": all(len(lg.changed) == 5 for lg in logs),
        "errors": [lg.error for lg in logs if lg.error],
        "hung_threads": r["hung"],
    }


def run_targets(deployments=("single", "procs2", "proxy"), scenarios=SCENARIOS,
                sequential: int = 10, burst: int = 30, active: int = 30,
                seconds: float = 60.0, url: str | None = None, pgids=(),
                client: str = "light") -> dict:
    """Every scenario on every deployment (or on the page at ``url``), with the load
    client ``client`` (CLIENTS)."""
    out = {"machine": machine(), "load": os.getloadavg(), "client": client, "runs": []}
    for kind in ([None] if url else deployments):
        target = (Target(f"served at {url}", url, pgids) if url else start_target(kind))
        res = {"deployment": target.name, "key": kind or "url"}
        try:
            if "sequential" in scenarios:
                res["sequential"] = scenario_sequential(target, sequential, client)
            else:                                       # one warm-up session
                visit(target.url, Visit(-1), time.monotonic(), client=client)
                target.idle()
            if "burst" in scenarios:
                res["burst"] = scenario_burst(target, burst, client=client)
                target.idle()
            if "active" in scenarios:
                res["active"] = scenario_active(target, active, seconds, client=client)
            res["bad_log_lines"] = target.bad_log()[:20]
        finally:
            target.stop()
        out["runs"].append(res)
        print(json.dumps(res, indent=1), flush=True)
    out["load_end"] = os.getloadavg()
    return out


def targets_markdown(res: dict) -> str:
    clients = {"light": "light clients (rel_light_client.py: the page's GET, then the "
                        "websocket protocol, no Bokeh models)",
               "light-ws": "light clients without the page's GET",
               "bokeh": "Bokeh client sessions"}[res.get("client", "bokeh")]
    end = (f", at the end {', '.join(f'{x:.1f}' for x in res['load_end'])}"
           if res.get("load_end") else "")
    lines = [f"- machine: {res['machine']}; load average at the start "
             f"{', '.join(f'{x:.1f}' for x in res['load'])}{end}; server, clients "
             f"({clients}, threads of one process) and nginx on the same machine "
             "(loopback)", ""]
    head = "| | " + " | ".join(r["deployment"] for r in res["runs"]) + " |"
    lines += [head, "|---" * (len(res["runs"]) + 1) + "|"]

    def row(label, fn):
        cells = []
        for r in res["runs"]:
            try:
                cells.append(fn(r))
            except (KeyError, TypeError):
                cells.append("—")
        lines.append(f"| {label} | " + " | ".join(str(c) for c in cells) + " |")

    row("Bokeh models in the pulled document",
        lambda r: ", ".join(map(str, (r.get("sequential") or r["burst"])["models"])))
    row("first session: server CPU", lambda r: f"{r['sequential']['first_session_cpu_s']:.2f} s")
    row("sequential sessions: server CPU per session (median / max)",
        lambda r: f"**{1e3 * r['sequential']['cpu_per_session_s']['median']:.0f} ms** / "
                  f"{1e3 * r['sequential']['cpu_per_session_s']['max']:.0f} ms")
    row("burst: complete within 60 s / at all; the last after",
        lambda r: f"{r['burst']['complete_within_60_s']} / {r['burst']['complete']} of "
                  f"{r['burst']['sessions']}; {r['burst']['all_complete_within_s']} s")
    row("burst: server CPU (until complete / with teardown)",
        lambda r: f"**{r['burst']['server_cpu_s']} s** / {r['burst']['server_cpu_with_teardown_s']} s")
    row("burst: server CPU by process", lambda r: " + ".join(
        f"{c:g}" for c in r["burst"]["server_cpu_by_process_s"].values()) + " s")
    row("burst: test clients' own CPU", lambda r: f"{r['burst']['client_cpu_s']} s")
    row("burst: the last session's five views after",
        lambda r: f"{r['burst']['all_five_views_within_s']} s")
    row("burst: connect → five views (median / max)",
        lambda r: f"{r['burst']['connect_to_five_views_s']['median']} s / "
                  f"{r['burst']['connect_to_five_views_s']['max']} s")
    row("active: scene updates / diagrams / lost updates",
        lambda r: f"{r['active']['updates']} / {r['active']['diagrams']} / "
                  f"{r['active']['lost_updates']}")
    row("active: scene update p95 (median)",
        lambda r: f"**{r['active']['scene_ms']['p95']} ms** ({r['active']['scene_ms']['median']} ms)")
    row("active: diagram p95 (median)",
        lambda r: f"**{r['active']['diagram_s']['p95']} s** ({r['active']['diagram_s']['median']} s)")
    row("active: server RSS baseline / peak / after close",
        lambda r: " / ".join(f"{r['active']['rss_mb'][k]}" for k in ("baseline", "peak", "after"))
        + " MB")
    row("active: server / clients CPU",
        lambda r: f"{r['active']['server_cpu_s']} s / {r['active']['client_cpu_s']} s")
    row("errors, server log tracebacks", lambda r: f"{sum(len(r.get(k, {}).get('errors', [])) for k in SCENARIOS)}, {len(r['bad_log_lines'])}")
    return "\n".join(lines)


def markdown(res: dict) -> str:
    return "\n".join([
        f"- machine: {res['machine']}; server and the {res['sessions']} client sessions on "
        "the same machine (loopback), clients as Bokeh client sessions in one process",
        f"- {res['rounds']} rounds of {res['sessions']} concurrent sessions, each moving "
        f"sliders for {res['seconds']:g} s once all are complete (staggered start, "
        f"{res['wall']:g} s in all), default diagram "
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


def _write_between(name: str, text: str) -> None:
    doc = ROOT / "RELIABILITY.md"
    body = doc.read_text()
    a, b = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    head, rest = body.split(a, 1)
    _, tail = rest.split(b, 1)
    doc.write_text(f"{head}{a}\n{text}\n{b}{tail}")


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--targets", action="store_true",
                    help="measure the classroom targets (sequential, burst, active) on each "
                         "deployment (or on --url) instead of the two-round classroom")
    ap.add_argument("--deployments", default="single,procs2,proxy",
                    help=f"with --targets: any of {', '.join(DEPLOYMENTS)} (default: all)")
    ap.add_argument("--scenarios", default=",".join(SCENARIOS),
                    help=f"with --targets: any of {', '.join(SCENARIOS)} (default: all)")
    ap.add_argument("--url", help="with --targets: measure the page served at this URL "
                                  "(e.g. http://localhost:5006/app) instead of starting one")
    ap.add_argument("--server-pgid", type=int, action="append", default=[],
                    help="with --url: process group(s) of that server, for its CPU and RSS "
                         "(e.g. $(ps -o pgid= -p PID)); without it they are not measured")
    ap.add_argument("--client", choices=CLIENTS, default=None,
                    help="the load client: light (default with --targets), light-ws, or "
                         "bokeh (default for the two-round classroom); see CLIENTS")
    ap.add_argument("--sequential", type=int, default=10, help="sequential sessions (10)")
    ap.add_argument("--burst", type=int, default=30, help="sessions in the burst (30)")
    ap.add_argument("--sessions", type=int, default=None,
                    help="active sessions (30 with --targets, else 24)")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--from-json", metavar="PATH",
                    help="do not run: take the figures of an earlier run's JSON")
    ap.add_argument("--write", action="store_true",
                    help="put the figures into RELIABILITY.md (between the load or the "
                         "targets markers)")
    args = ap.parse_args(argv)
    # a TERM (timeout, kill) unwinds like Ctrl-C: the servers started here are stopped
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    RESULTS.mkdir(parents=True, exist_ok=True)
    if args.targets:
        if args.from_json:
            res = json.loads(Path(args.from_json).read_text())
        else:
            res = run_targets(tuple(args.deployments.split(",")),
                              tuple(args.scenarios.split(",")), args.sequential, args.burst,
                              args.sessions or 30, args.seconds, args.url, args.server_pgid,
                              args.client or "light")
            (RESULTS / "targets.json").write_text(json.dumps(res, indent=1))
            print(f"figures: {RESULTS / 'targets.json'}")
        text = targets_markdown(res)
        print(text)
        if args.write:
            _write_between("targets", text)
        return 0
    sessions = args.sessions or 24
    if args.from_json:
        res = json.loads(Path(args.from_json).read_text())
    else:
        res = run(sessions, args.seconds, args.rounds, client=args.client or "bokeh")
        (RESULTS / f"load-{sessions}.json").write_text(json.dumps(res, indent=1))
    text = markdown(res)
    print(text)
    print(json.dumps({k: v for k, v in res.items() if k != "per_session"}, indent=1))
    if args.write:
        _write_between("load", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
