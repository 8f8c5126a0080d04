"""The served app in headless Chromium: views, sliders, scenes, links, messages, log.

Plot data is read from the page's Bokeh document by renderer name. Timings (slider to
repaint, r change to complete diagram) are written to test-results/app_figures.md.
"""
import json
import re
import statistics
import time
from pathlib import Path
from urllib.parse import parse_qs, urlparse


RESULTS = Path(__file__).resolve().parents[2] / "test-results"

VIEWS = ("displacement", "phase", "impact_map", "poincare", "bifurcation")

JS = """
window.ie = {
  model: (n) => Bokeh.documents[0].get_model_by_name(n),
  data: (n) => Bokeh.documents[0].get_model_by_name(n).data_source.data,
  len: (n) => { const d = Bokeh.documents[0].get_model_by_name(n).data_source.data;
                const k = Object.keys(d)[0]; return d[k].length; },
  sum: (n, col) => { let s = 0; for (const v of ie.data(n)[col]) s += v; return s; },
  title: (n) => Bokeh.documents[0].get_model_by_name(n).title.text,
};
"""
READY = """() => {
  if (!(window.Bokeh && Bokeh.documents.length)) return false;
  const doc = Bokeh.documents[0];
  for (const n of %s) {
    const m = doc.get_model_by_name(n);
    if (!m) return false;
    const d = m.data_source.data; const k = Object.keys(d)[0];
    if (!d[k] || d[k].length === 0) return false;
  }
  return doc.get_model_by_name('bifurcation_figure').title.text.includes('complete');
}""" % json.dumps(list(VIEWS))

FIGURES: dict = {}


STATE = """() => {
  if (!(window.Bokeh && Bokeh.documents.length)) return 'no Bokeh document';
  const doc = Bokeh.documents[0];
  return JSON.stringify(%s.map((n) => {
    const m = doc.get_model_by_name(n);
    if (!m) return n + ': missing';
    const d = m.data_source.data;
    return n + ': ' + d[Object.keys(d)[0]].length;
  })) + ' ' + doc.get_model_by_name('bifurcation_figure').title.text;
}""" % json.dumps(list(VIEWS))


def open_app(page, server, query: str = ""):
    page.goto(server.url + query)
    try:
        page.wait_for_function(READY, timeout=30_000, polling=100)
    except Exception:
        raise AssertionError(f"page not ready: {page.evaluate(STATE)}") from None
    page.evaluate(JS)


def open_settings(page) -> None:
    """Open the settings drawer (every setting but ω, r, c, g; built when first opened)."""
    if not page.locator(".ie-drawer").first.is_visible():
        page.locator(".ie-sidebar-toggle button").click()
    page.locator(".ie-drawer").first.wait_for(state="visible", timeout=10_000)


def close_settings(page) -> None:
    if page.locator(".ie-drawer").first.is_visible():
        page.locator(".ie-drawer-close button").click()
        page.locator(".ie-drawer").first.wait_for(state="hidden", timeout=10_000)


def snapshot(page) -> dict:
    return page.evaluate("""() => ({
      disp: [ie.len('displacement'), ie.sum('displacement', 'x')],
      phase: [ie.len('phase'), ie.sum('phase', 'v')],
      imap: [ie.len('impact_map'), ie.sum('impact_map', 'v')],
      bif: [ie.len('bifurcation'), ie.sum('bifurcation', 'v')],
      marker: ie.model('bifurcation_marker').location,
      bif_title: ie.title('bifurcation_figure'),
    })""")


def text(page, css_class: str) -> str:
    """Visible text of a Panel pane (its content lives in the host's shadow root)."""
    return page.locator(f".{css_class}").first.evaluate(
        "e => Array.from((e.shadowRoot || e).children)"
        ".filter(c => !['STYLE', 'LINK'].includes(c.tagName))"
        ".map(c => c.innerText).join(' ')")


def query(page) -> dict:
    return {k: v[-1] for k, v in parse_qs(urlparse(page.url).query).items()}


def watch_reconnect(page) -> None:
    """Count BokehJS's reconnect events on the page's document from now on:
    ``client_reconnected`` (socket open, session acknowledged, document pulled again) and
    ``document_ready`` (the redrawn views are ready; app.panel_fixes.RECONNECT_JS makes
    it come again after a reconnect)."""
    page.evaluate("""() => { window.__ieReconnected = 0; window.__ieReady = 0;
      const doc = Bokeh.documents[0];
      doc.on_event('client_reconnected', () => { window.__ieReconnected += 1 });
      doc.on_event('document_ready', () => { window.__ieReady += 1 }) }""")


def wait_reconnected(page, describe=lambda: "") -> None:
    """Wait (after ``watch_reconnect``) until the page has reconnected and redrawn its
    views. Keys pressed into the old widgets while it redraws are lost, as they would be
    for a person. ``describe()`` adds context to a failure."""
    try:                                  # BokehJS retries after 1, 2, 4, 8 ... s
        page.wait_for_function("() => window.__ieReconnected > 0", timeout=60_000, polling=200)
    except Exception:
        raise AssertionError(f"the page never reconnected; {describe()}") from None
    try:
        page.wait_for_function("() => window.__ieReady > 0", timeout=30_000, polling=100)
    except Exception:
        raise AssertionError(f"the page was not redrawn after the reconnect; {describe()}") \
            from None


def handle(page, name):
    return page.locator(f".ie-w-{name} .noUi-handle").first


def test_page_loads_with_five_plots_holding_data(page, server):
    open_app(page, server)
    for name in VIEWS:
        assert page.evaluate(f"ie.len('{name}')") > 0, name
    assert not page.locator(".ie-message").is_visible()
    assert "Motion:" in text(page, "ie-badge")
    assert page.evaluate("ie.model('bifurcation_marker').location") == 2
    page.wait_for_function("() => true")
    assert text(page, "ie-diagram-status").startswith("complete: 400 ω values")
    RESULTS.mkdir(exist_ok=True)
    page.screenshot(path=str(RESULTS / "app.png"), full_page=True)


def test_omega_slider_moves_scene_views_and_marker_not_diagram(page, server):
    open_app(page, server)
    before = snapshot(page)
    h = handle(page, "omega")
    h.focus()
    for _ in range(5):
        h.press("ArrowRight")
    page.wait_for_function("() => Math.abs(ie.model('bifurcation_marker').location - 2.05) < 1e-9",
                           timeout=10_000)
    page.wait_for_timeout(300)        # let any (wrong) diagram update arrive
    after = snapshot(page)
    assert after["disp"] != before["disp"] and after["phase"] != before["phase"]
    assert after["imap"] != before["imap"]
    assert after["bif"] == before["bif"] and after["bif_title"] == before["bif_title"]
    page.wait_for_function("() => location.search.includes('omega=2.05')", timeout=5_000)


def test_r_change_restarts_diagram(page, server):
    open_app(page, server)
    before = snapshot(page)
    h = handle(page, "r")
    h.focus()
    times = []
    for i in range(1, 6):
        r = f"{0.8 - 0.01 * i:.2f}"
        t0 = time.perf_counter()
        h.press("ArrowLeft")
        page.wait_for_function(
            f"() => ie.title('bifurcation_figure').includes('r = {r.rstrip('0')},') && "
            "ie.title('bifurcation_figure').includes('complete') && ie.len('bifurcation') > 0",
            timeout=20_000, polling="raf")
        times.append(time.perf_counter() - t0)
    after = snapshot(page)
    assert after["bif"] != before["bif"] and after["disp"] != before["disp"]
    assert text(page, "ie-diagram-status").startswith("complete")
    # timed for app_figures.md only: speed is judged in bench/, not by a test's clock
    FIGURES["diagram"] = times


def test_scene_picker_loads_its_settings(page, server):
    open_app(page, server)
    page.locator(".ie-scene select").select_option(label="Fig 7b · ψ=3T/8")
    page.wait_for_function("() => Math.abs(ie.model('bifurcation_marker').location - 2.8) < 1e-9",
                           timeout=10_000)
    page.wait_for_function("() => ie.title('poincare_figure').startsWith('Poincaré map, ψ = 0.375 T')",
                           timeout=10_000)
    assert page.locator(".ie-w-omega input").first.input_value() == "2.800"
    assert "Fig. 7(b)" in text(page, "ie-caption")
    # the link names the scene, and no number (all are the scene's)
    page.wait_for_function("() => location.search === '?scene=fig7b'", timeout=5_000)
    page.screenshot(path=str(RESULTS / "app-fig7b.png"), full_page=True)


def test_url_with_parameters_restores_them(page, server):
    open_app(page, server, "?omega=1.2&r=0.6&c=0.1&psi=1.3&bif_n=200&method=rk45")
    assert page.evaluate("ie.model('bifurcation_marker').location") == 1.2
    assert page.locator(".ie-w-omega input").first.input_value() == "1.200"
    assert page.locator(".ie-w-r input").first.input_value() == "0.600"
    title = page.evaluate("ie.title('bifurcation_figure')")
    assert "r = 0.6," in title and "c = 0.1," in title
    assert "rk45" in text(page, "ie-badge")
    q = query(page)
    assert float(q["omega"]) == 1.2 and float(q["r"]) == 0.6
    assert abs(float(q["psi"]) - 1.3) < 1e-9 and q["method"] == "rk45"
    assert not page.locator(".ie-message").is_visible()


def test_url_with_garbage_shows_message_and_defaults(page, server):
    open_app(page, server, "?omega=banana&r=2&c=nan&psi=<b>x</b>")
    msg = page.locator(".ie-message")
    assert msg.is_visible()
    text_ = text(page, "ie-message")
    for field in ("omega", "r", "c", "psi"):
        assert re.search(rf"\b{field}\b", text_), (field, text_)
    assert page.evaluate("ie.model('bifurcation_marker').location") == 2
    for name in VIEWS:
        assert page.evaluate(f"ie.len('{name}')") > 0, name


def test_bad_widget_input_shows_message_and_keeps_scene(page, server):
    open_app(page, server)
    before = snapshot(page)
    open_settings(page)
    box = page.locator(".ie-w-m input").first
    box.fill("-1")
    box.press("Enter")
    msg = page.locator(".ie-message")
    msg.wait_for(state="visible", timeout=10_000)
    assert re.search(r"\bm\b", text(page, "ie-message"))
    page.wait_for_timeout(300)
    assert snapshot(page) == before
    box.fill("1.5")
    box.press("Enter")
    msg.wait_for(state="hidden", timeout=10_000)


def test_accuracy_readout_and_csv_download(page, server):
    open_app(page, server)
    open_settings(page)
    page.get_by_text("Accuracy", exact=True).click()
    page.get_by_role("button", name="Compare methods").click()
    page.wait_for_function("() => true")
    deadline = time.monotonic() + 30
    while "rk45" not in text(page, "ie-accuracy-out") and time.monotonic() < deadline:
        page.wait_for_timeout(100)
    table = text(page, "ie-accuracy-out")
    assert "exact" in table and "rk4" in table and "rk45" in table, table
    page.locator(".ie-accuracy-close button").click()
    page.get_by_text("Downloads", exact=True).click()
    with page.expect_download(timeout=15_000) as info:
        page.get_by_text("Impacts (CSV)").click()
    download = info.value
    assert download.suggested_filename == "impacts_omega2_r0.8_c0.05_g0.csv"
    lines = [line for line in Path(download.path()).read_text().splitlines()
             if not line.startswith("#")]
    assert lines[0] == "t,phase,v_before,v_after"
    assert len(lines) - 1 == page.evaluate("ie.len('impact_map')")


LATENCY_JS = """() => {
  const src = ie.model('displacement').data_source;
  window.__lat = new Promise((resolve, reject) => {
    setTimeout(() => reject(new Error('x(t) not repainted 20 s after the key')), 20000);
    let t0 = null;
    window.addEventListener('keydown', () => { t0 = performance.now(); },
                            {once: true, capture: true});
    const done = () => requestAnimationFrame(() => requestAnimationFrame(
        () => resolve(performance.now() - t0)));
    src.properties.data.change.connect(done);
  });
}"""


def test_each_omega_step_repaints_the_scene(page, server):
    """Every key step repaints x(t) (the wait fails otherwise); the latencies, new values
    each time and nothing cached, go to app_figures.md, not into an assertion."""
    open_app(page, server)
    h = handle(page, "omega")
    h.focus()
    samples = []
    for _ in range(16):
        page.evaluate(LATENCY_JS)
        h.press("ArrowRight")
        samples.append(page.evaluate("window.__lat"))
    samples = samples[1:]                   # the first move also warms the page
    FIGURES["latency"] = samples


#: Bokeh models a page may hold at the paper defaults (explore, the first page): 182
#: measured with seven figures (the five views, the animation, the Lyapunov strip), the
#: bar of ω, r, c, g, the header and the information line. The settings drawer, compare
#: and research modes and the accuracy panel are built on use (tests/browser/test_modes.py
#: counts each mode when opened).
MODEL_BUDGET = 182


def test_page_bokeh_models_within_budget(page, server):
    """A count, not a timing: every model is built, serialised and sent per session."""
    open_app(page, server)
    n = page.evaluate("Bokeh.documents[0].all_models.size")
    assert n <= MODEL_BUDGET, n
    # nothing of the browser's details is kept (each new page would send seven patches)
    assert page.evaluate("Bokeh.documents[0].get_model_by_name('browser_info')") is None


def test_server_log_has_no_traceback(server):
    """Runs last in this module: everything above went through the same server."""
    time.sleep(0.5)
    log = server.log.read_text(errors="replace")
    assert "Traceback" not in log, log[-3000:]
    assert " ERROR " not in log and "Exception" not in log, log[-3000:]
    _write_figures()


def _write_figures():
    lines = ["# App figures (headless Chromium, loopback, this machine)", ""]
    if "latency" in FIGURES:
        s = FIGURES["latency"]
        lines.append(f"- omega slider move to repainted scene views: median "
                     f"{statistics.median(s):.0f} ms, min {min(s):.0f}, max {max(s):.0f} "
                     f"over {len(s)} moves (keyboard step 0.01 from omega = 2, paper defaults)")
    if "diagram" in FIGURES:
        s = [1e3 * x for x in FIGURES["diagram"]]
        lines.append(f"- r change to complete 400-value bifurcation diagram in the page: "
                     f"median {statistics.median(s):.0f} ms, min {min(s):.0f}, "
                     f"max {max(s):.0f} over {len(s)} changes")
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "app_figures.md").write_text("\n".join(lines) + "\n")
