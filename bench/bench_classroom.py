"""Classroom page benchmark (issue 10): the animation's frame rate in headless Chromium,
alone and while other sessions move sliders on the same server; websocket frames while
it plays; Bokeh models per page; the windowed x(t) job.

    panel serve app/app.py --port 5006 &
    .venv/bin/python bench/bench_classroom.py http://127.0.0.1:5006/app [--students 8]

Frame rate: the animation plays for 5 s at 1x; a frame is a change of the mass's time
in the page (read every animation frame of the page); median of 3 runs. The page's own
animation-frame rate while paused is printed first: on a loaded machine headless
Chromium itself runs fewer than 60, which caps any animation. "Students" are
Bokeh client sessions (bokeh.client) that each move ω every 0.5 s during the runs; their
own CPU is in this process, apart from the server's. Window job: the time of
``app.compute.window_columns`` in this process after a warm-up, median of 5, for a 20 s
window and the whole 20000 s record at ω = 2.81.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]
READY = """() => window.Bokeh && Bokeh.documents.length &&
  Bokeh.documents[0].get_model_by_name('bifurcation_figure').title.text.includes('complete')"""
COUNT_FRAMES = """(seconds) => new Promise((resolve) => {
  const src = Bokeh.documents[0].get_model_by_name('animation_mass').data_source;
  let last = null, frames = 0; const t0 = performance.now();
  function tick(now) {
    const t = src.data.t[0];
    if (t !== last) { frames++; last = t; }
    if (now - t0 < seconds * 1000) requestAnimationFrame(tick);
    else resolve(frames / ((now - t0) / 1000));
  }
  requestAnimationFrame(tick);
})"""


#: The page's own animation-frame rate (what any animation can get), measured paused.
COUNT_RAF = """(seconds) => new Promise((resolve) => {
  let n = 0; const t0 = performance.now();
  function tick(now) {
    n++;
    if (now - t0 < seconds * 1000) requestAnimationFrame(tick); else resolve(n / ((now - t0) / 1000));
  }
  requestAnimationFrame(tick);
})"""


def fps_runs(url: str, runs: int = 3, seconds: float = 5.0) -> tuple[list, list, int]:
    from playwright.sync_api import sync_playwright
    rates, frames_seen = [], []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True,
                                    args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1280, "height": 720})
        frames = {"n": 0}
        page.on("websocket", lambda ws: ws.on("framereceived",
                                               lambda _: frames.__setitem__("n", frames["n"] + 1)))
        page.goto(url + "?scene=fig4")
        page.wait_for_function(READY, timeout=60_000, polling=200)
        page.wait_for_timeout(1000)
        models = page.evaluate("() => Bokeh.documents[0]._all_models.size")
        print(f"  browser animation frames/s while paused: {page.evaluate(COUNT_RAF, 3.0):.1f}")
        for _ in range(runs):
            page.locator(".ie-anim-play button").click()
            page.wait_for_timeout(200)
            before = frames["n"]
            rates.append(page.evaluate(COUNT_FRAMES, seconds))
            frames_seen.append(frames["n"] - before)
            page.locator(".ie-anim-play button").click()
        browser.close()
    return rates, frames_seen, models


def students(url: str, n: int, stop: threading.Event) -> list[threading.Thread]:
    """n Bokeh client sessions moving ω every 0.5 s until ``stop``."""
    import panel.models  # noqa: F401  (registers Panel's Bokeh models for the client)
    from bokeh.client import pull_session

    def run(i):
        session = pull_session(url=url)
        doc = session.document
        sliders = [m for m in doc.models if type(m).__name__ == "Slider"
                   and m.name != "animation_time" and m.start < 2 < m.end]     # ω
        assert sliders, "no ω slider in the page"
        k = 0
        while not stop.is_set():
            k += 1
            for s in sliders[:1]:
                session.document.add_next_tick_callback(
                    lambda s=s, k=k: setattr(s, "value", 1.5 + 0.01 * ((i * 7 + k) % 100)))
            time.sleep(0.5)
        session.close()
    threads = [threading.Thread(target=run, args=(i,), daemon=True) for i in range(n)]
    for t in threads:
        t.start()
    return threads


def window_times() -> dict:
    from app import compute, state
    run = state.validate({**state.defaults(), "omega": 2.81, "t_end": 20000.0})
    out = {}
    for name, (a, b) in {"20 s window": (19980.0, 20000.0),
                         "whole 20000 s (envelope)": (250.0, 20000.0)}.items():
        compute.window_columns(run, a, b, 1000)
        times = []
        for _ in range(5):
            tic = time.perf_counter()
            compute.window_columns(run, a, b, 1000)
            times.append(time.perf_counter() - tic)
        out[name] = statistics.median(times)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("url", nargs="?", default="http://127.0.0.1:5006/app")
    ap.add_argument("--students", type=int, default=8)
    args = ap.parse_args()
    rates, frames, models = fps_runs(args.url)
    print(f"Bokeh models per page: {models}")
    print(f"animation alone: {statistics.median(rates):.1f} frames/s (runs {rates}); "
          f"websocket frames received while playing: {frames}")
    stop = threading.Event()
    cpu0 = time.process_time()
    threads = students(args.url, args.students, stop)
    time.sleep(2)
    rates, frames, _ = fps_runs(args.url)
    stop.set()
    for t in threads:
        t.join(5)
    print(f"animation with {args.students} students moving ω every 0.5 s: "
          f"{statistics.median(rates):.1f} frames/s (runs {rates}); websocket frames "
          f"received while playing: {frames}; students' CPU in this process "
          f"{time.process_time() - cpu0:.1f} s")
    for name, seconds in window_times().items():
        print(f"window_columns, {name}: {seconds * 1e3:.1f} ms (median of 5)")


if __name__ == "__main__":
    main()
