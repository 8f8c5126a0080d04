"""The stability readout, the Lyapunov strip and the branch overlay in headless Chromium.

Data are read from the page's Bokeh document by renderer name (see test_app_browser)."""
import time

import pytest
from test_app_browser import JS, RESULTS, text

STRIP_READY = """() => {
  if (!(window.Bokeh && Bokeh.documents.length)) return false;
  const doc = Bokeh.documents[0];
  const bif = doc.get_model_by_name('bifurcation_figure');
  const strip = doc.get_model_by_name('lyapunov');
  const readout = doc.get_model_by_name('stability_readout');
  return !!(bif && strip && readout) && bif.title.text.includes('complete')
    && strip.data_source.data.omega.length > 0 && !readout.text.includes('computing');
}"""


def open_page(page, server, query=""):
    page.goto(server.url + query)
    page.wait_for_function(STRIP_READY, timeout=60_000, polling=200)
    page.evaluate(JS)


def test_readout_and_strip_at_paper_defaults(page, server):
    open_page(page, server)
    readout = text(page, "ie-stability")
    assert "1-impact period-1" in readout and "stable" in readout, readout
    data = page.evaluate("""() => { const d = ie.data('lyapunov');
        return {n: d.omega.length, lam: Array.from(d.lyapunov), omega: Array.from(d.omega)}; }""")
    assert data["n"] == 400                       # one point per swept value
    assert any(v > 0 for v in data["lam"])        # the chaos bands of the paper's Fig. 3
    shared = page.evaluate("ie.model('lyapunov_figure').x_range.id === "
                           "ie.model('bifurcation_figure').x_range.id")
    assert shared
    assert page.evaluate("ie.model('lyapunov_zero').location") == 0


BRANCHES_READY = """() => {
  const doc = Bokeh.documents[0];
  const r = doc.get_model_by_name('branches_stable');
  return !!r && r.data_source.data.xs.length > 0;
}"""


@pytest.mark.parametrize("query", ["?branches=1", "?r=0.6&branches=1"])
def test_branch_overlay_from_the_url(page, server, query):
    open_page(page, server, query)
    page.wait_for_function(BRANCHES_READY, timeout=90_000, polling=200)
    counts = page.evaluate("""() => ({
        stable: ie.data('branches_stable').xs.length,
        unstable: ie.data('branches_unstable').xs.length,
        events: ie.data('branch_events').x.length,
        labels: ie.data('branch_events').text.filter((t) => t).join(' '),
        lyapunov: ie.len('lyapunov') })""")
    assert counts["stable"] > 0 and counts["unstable"] > 0 and counts["events"] > 0, counts
    assert "PD" in counts["labels"] and counts["lyapunov"] == 400, counts
    assert page.locator(".ie-w-branches input").first.is_checked()
    page.set_viewport_size({"width": 1280, "height": 720})
    page.evaluate("() => window.scrollTo(0, document.body.scrollHeight)")
    page.wait_for_timeout(500)
    RESULTS.mkdir(exist_ok=True)
    name = "stability-r06.png" if "r=0.6" in query else "stability.png"
    page.screenshot(path=str(RESULTS / name))


def test_branch_checkbox_switches_the_overlay_and_the_url(page, server):
    open_page(page, server, "?bif_n=100")
    assert page.evaluate("Bokeh.documents[0].get_model_by_name('branches_stable')") is None
    box = page.locator(".ie-w-branches input").first      # above the diagram
    box.check()
    page.wait_for_function(BRANCHES_READY, timeout=90_000, polling=200)
    page.wait_for_function("() => location.search.includes('branches=1')", timeout=5_000)
    box.uncheck()
    page.wait_for_function("() => !ie.model('branches_stable').visible && "
                           "ie.data('branches_stable').xs.length === 0", timeout=10_000)
    page.wait_for_function("() => location.search.includes('branches=0')", timeout=5_000)


def test_server_log_has_no_traceback(server):
    time.sleep(0.5)
    log = server.log.read_text(errors="replace")
    assert "Traceback" not in log, log[-3000:]
    assert " ERROR " not in log and "Exception" not in log, log[-3000:]
    RESULTS.mkdir(exist_ok=True)
