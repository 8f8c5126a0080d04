"""Click an orbit: from a tap on a branch of the diagram's overlay to the scene views on
that orbit (target 500 ms).

Two measurements, each a median over taps on distinct unstable branch points near
omega = 2.8 ... 3.3 at r = 0.6 (no cache holds their scenes), after one warm-up tap:

- server: in process, a session without a browser (its jobs run inline): the tap's
  handler (nearest branch point, Newton on the settings' grid) and everything it sets
  off until the scene views hold the orbit (scene run, section, caption's orbit check);
- page: ``panel serve app/app.py`` and headless Chromium (``--browser``): from the
  mouse click to the Poincaré view's first point holding the orbit's state, as the page
  sees it (websocket both ways, Bokeh's update included).

    PYTHONPATH=. python bench/bench_orbit_tap.py [--browser] [--taps 9]

Prints only; figures from a shared machine are noisy.
"""
from __future__ import annotations

import argparse
import os
import signal
import socket
import statistics
import subprocess
import sys
import time
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import impactlib as il  # noqa: E402

ARGS = {"r": "0.6", "branches": "1", "bif_min": "1.5", "bif_max": "3.5", "bif_n": "40"}


def targets(branch_set, k: int):
    """``k`` unstable admissible branch points (param, impact velocity) spread over
    omega in [2.8, 3.3]."""
    pts = []
    for b in branch_set.branches:
        ok = ~b.stable & b.admissible & (b.param > 2.8) & (b.param < 3.3)
        pts += [(float(b.param[i]), float(b.impact_velocities[i, 0]))
                for i in np.flatnonzero(ok)]
    pts.sort()
    idx = np.linspace(0, len(pts) - 1, min(k, len(pts))).round().astype(int)
    return [pts[i] for i in idx]


def server_side(n: int) -> list[float]:
    from app.explorer import Explorer
    e = Explorer(args=ARGS)
    assert e.diagram.job.done.wait(300) and e.diagram.branch_job.done.wait(600)
    times = []
    for x, y in targets(e.branches.shown, n + 1):
        e.settings.omega = 2.0                  # off the orbit between taps
        tic = time.perf_counter()
        e.bifurcation._on_tap(types.SimpleNamespace(x=x, y=y))
        times.append(time.perf_counter() - tic)
        if e.run.orbit_x0 is None:
            print(f"  no orbit found at the grid values next to ({x:.4f}, {y:.4f})")
            continue
        assert e.section["t"][0] == 0.0
    return times[1:]


def page_side(n: int) -> list[float]:
    from playwright.sync_api import TimeoutError as PlaywrightTimeout
    from playwright.sync_api import sync_playwright
    sys.path.insert(0, str(ROOT / "tests" / "browser"))
    from conftest import CHROMIUM, CHROMIUM_ARGS
    from test_app_browser import JS, READY
    from test_diagram_browser import TO_PAGE
    from test_stability_browser import BRANCHES_READY
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    panel = Path(sys.executable).with_name("panel")
    proc = subprocess.Popen([str(panel), "serve", "app/app.py", "--address", "127.0.0.1",
                             "--port", str(port), "--allow-websocket-origin",
                             f"127.0.0.1:{port}"], cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    times = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True,
                                         args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            query = "&".join(f"{k}={v}" for k, v in ARGS.items())
            deadline = time.monotonic() + 90
            while True:
                try:
                    page.goto(f"http://127.0.0.1:{port}/app?{query}")
                    break
                except Exception:
                    if time.monotonic() > deadline:
                        raise
                    time.sleep(0.5)
            page.wait_for_function(READY, timeout=120_000, polling=100)
            page.evaluate(JS)
            page.wait_for_function(BRANCHES_READY, timeout=300_000, polling=200)
            pts = page.evaluate("""() => { const d = ie.data('branches_unstable'); const out = [];
                for (let i = 0; i < d.xs.length; i++) for (let j = 0; j < d.xs[i].length; j++)
                  if (d.xs[i][j] > 2.8 && d.xs[i][j] < 3.3) out.push([d.xs[i][j], d.ys[i][j]]);
                return out; }""")
            pts.sort()
            grid = {}                    # one point per 0.01 of omega (the slider's grid)
            for x, y in pts:
                grid.setdefault(round(x, 2), (x, y))
            pts = list(grid.values())
            pick = [pts[i] for i in np.linspace(0, len(pts) - 1, n + 1).round().astype(int)]
            for x, y in pick:
                url = page.evaluate("() => location.href")    # as the page writes it
                px, py = page.evaluate(TO_PAGE, ["bifurcation_figure", x, y])
                page.wait_for_timeout(800)      # not a double tap with the last one
                tic = time.perf_counter()
                page.mouse.click(px, py)
                try:
                    page.wait_for_function("(url) => location.href !== url", arg=url,
                                           timeout=5_000, polling="raf")
                except PlaywrightTimeout:   # the orbit shown already (a neighbour's grid)
                    print(f"  no change from a tap at ({x:.4f}, {y:.4f})")
                    continue
                if "orbit_x0=" not in page.url:
                    print(f"  no orbit found at the grid values next to ({x:.4f}, {y:.4f})")
                    continue
                page.wait_for_function(
                    "() => { const q = new URLSearchParams(location.search); "
                    "const d = ie.data('poincare'); return d.t[0] === 0 && "
                    "Math.abs(d.x[0] - Number(q.get('orbit_x0'))) < 1e-9; }",
                    timeout=20_000, polling="raf")
                times.append(time.perf_counter() - tic)
            browser.close()
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(10)
    return times[1:]


def report(what: str, times: list[float]) -> None:
    ms = [1e3 * t for t in times]
    print(f"{what}: median {statistics.median(ms):.0f} ms, min {min(ms):.0f}, "
          f"max {max(ms):.0f} ms over {len(ms)} taps")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--taps", type=int, default=9)
    ap.add_argument("--browser", action="store_true", help="also time it in Chromium")
    args = ap.parse_args()
    il.warmup()
    report("tap -> scene views, server (in process)", server_side(args.taps))
    if args.browser:
        report("tap -> Poincare view on the orbit, page (Chromium)", page_side(args.taps))


if __name__ == "__main__":
    main()
