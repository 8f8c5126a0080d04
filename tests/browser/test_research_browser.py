"""Research mode in headless Chromium: the regime map and the basins fill when their tab
opens, and a tap on each changes the scene. Screenshots go to test-results/."""
import time
from pathlib import Path

from playwright.sync_api import expect
from test_app_browser import RESULTS, open_app, query, text
from test_diagram_browser import tap

FILLED = """(name) => {
  const m = Bokeh.documents[0].get_model_by_name(name);
  if (!m) return false;
  const img = m.data_source.data.image[0];
  if (!img || img.length < 4) return false;
  for (const v of img) if (Number.isNaN(v)) return false;
  return true;
}"""


def wait_complete(page, css: str, timeout: float = 60.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        status = text(page, css)
        if status.startswith(("complete", "partial", "not computed")):
            return status
        page.wait_for_timeout(200)
    raise AssertionError(f"{css}: {text(page, css)}")


#: Where a figure's canvas sits on the page.
RECT = """(name) => {
  const m = Bokeh.documents[0].get_model_by_name(name);
  const r = Bokeh.index.find_one_by_id(m.id).canvas_view.el.getBoundingClientRect();
  return [r.left, r.top, r.width, r.height];
}"""


def settled(page) -> None:
    """The scene's results are all in: the stability readout is no longer computing."""
    deadline = time.monotonic() + 20
    while "computing" in (readout := text(page, "ie-stability")):
        assert time.monotonic() < deadline, readout
        page.wait_for_timeout(100)


def disp_sum(page) -> float:
    return page.evaluate("ie.sum('displacement', 'x')")


def test_regime_map_and_basins_fill_and_taps_change_the_scene(page, server):
    open_app(page, server, "?omega=2.62&r=0.8")
    assert page.evaluate("Bokeh.documents[0].get_model_by_name('regime_map_figure')") is None
    page.locator(".ie-w-mode button", has_text="Research").click()
    page.wait_for_function(FILLED, arg="regime_map", timeout=60_000)
    status = wait_complete(page, "ie-map-status")
    assert status.startswith("complete: 100 rows"), status
    page.wait_for_function("() => ie.model('regime_map_current').data_source.data.x[0] === 2.62",
                           timeout=10_000)
    page.wait_for_timeout(300)
    page.locator(".ie-research").screenshot(path=str(RESULTS / "regime_map.png"))

    with page.expect_download(timeout=15_000) as info:
        page.locator(".ie-map-csv").get_by_text("CSV").click()
    lines = Path(info.value.path()).read_text().splitlines()
    assert lines[0].startswith("# m = ") and "# map_x = omega" in lines
    body = [line for line in lines if not line.startswith("#")]
    assert body[0] == "omega,r,m,n,class" and len(body) == 1 + 100 * 100

    before = disp_sum(page)
    settled(page)
    rect = page.evaluate(RECT, "regime_map_figure")
    tap(page, "regime_map_figure", 2.8, 0.6)
    page.wait_for_function("() => Math.abs(ie.model('bifurcation_marker').location - 2.8) < 0.03",
                           timeout=10_000)
    expect(page.locator(".ie-w-r input").first).to_have_value("0.600", timeout=10_000)
    page.wait_for_function(f"() => ie.sum('displacement', 'x') !== {before}", timeout=10_000)
    # results arriving (scene, badge, stability) never move the figure under the pointer
    page.wait_for_timeout(200)
    settled(page)
    assert page.evaluate(RECT, "regime_map_figure") == rect

    # back to the paper's r = 0.8, omega = 2.62 and on to the basins tab
    tap(page, "regime_map_figure", 2.62, 0.8)
    page.wait_for_function("() => Math.abs(ie.model('bifurcation_marker').location - 2.62) < 0.03",
                           timeout=10_000)
    page.locator(".bk-tab", has_text="Basins").first.click()
    page.wait_for_function(FILLED, arg="basins", timeout=60_000)
    status = wait_complete(page, "ie-basins-status")
    assert status.startswith("complete: 100 rows"), status
    legend = text(page, "ie-basins-legend")
    assert "1-impact period-1" in legend, legend
    page.wait_for_timeout(300)
    page.locator(".ie-research").screenshot(path=str(RESULTS / "basins.png"))

    before = disp_sum(page)
    x_end = page.evaluate("ie.model('basins_figure').x_range.end")
    tap(page, "basins_figure", 0.5 * x_end, 0.3)
    page.wait_for_function("() => location.search.includes('x0=')", timeout=10_000)
    x0 = float(query(page)["x0"])          # (its box is in a card not opened)
    assert abs(x0 - 0.5 * x_end) < 0.05 * x_end, x0
    page.wait_for_function(f"() => ie.sum('displacement', 'x') !== {before}", timeout=10_000)
    start = page.evaluate("ie.model('basins_start').data_source.data.x[0]")
    assert abs(start - x0) < 1e-9


def test_server_log_has_no_traceback_after_research(server):
    log = server.log.read_text(errors="replace")
    assert "Traceback" not in log, log[-3000:]
