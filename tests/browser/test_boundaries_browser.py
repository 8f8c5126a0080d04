"""The boundary curves over the regime map in headless Chromium: with ``boundaries=1`` the
period-doubling, saddle-node and grazing renderers fill once the map is opened; the
picture goes to test-results/ (docs/boundaries.png is that picture, looked at and
committed)."""
import time
from pathlib import Path

from test_app_browser import open_app, text
from test_research_browser import FILLED, wait_complete

RESULTS = Path(__file__).resolve().parents[2] / "test-results"

HOLDS = """(names) => names.every((name) => {
  const m = Bokeh.documents[0].get_model_by_name(name);
  return m && m.data_source.data.xs.length > 0;
})"""


def test_boundary_renderers_fill_over_the_regime_map(page, server):
    open_app(page, server, "?omega=2.62&r=0.8&boundaries=1")
    page.locator(".ie-w-mode button", has_text="Research").click()
    page.wait_for_function(FILLED, arg="regime_map", timeout=120_000)
    wait_complete(page, "ie-map-status", timeout=120.0)
    page.wait_for_function(HOLDS, arg=["boundary_pd", "boundary_sn", "boundary_grazing"],
                           timeout=120_000)
    # the picture once the overlay is done with the map's regions too (complete, or cut
    # by its time bound)
    deadline = time.monotonic() + 180
    while not ("regions of the map" in (status := text(page, "ie-boundaries-status"))
               or "stopped at the time bound" in status):
        assert time.monotonic() < deadline, status
        page.wait_for_timeout(200)
    page.wait_for_timeout(500)
    RESULTS.mkdir(exist_ok=True)
    page.locator(".ie-research").screenshot(path=str(RESULTS / "boundaries.png"))


def test_server_log_has_no_traceback_after_boundaries(server):
    log = server.log.read_text(errors="replace")
    assert "Traceback" not in log, log[-3000:]
