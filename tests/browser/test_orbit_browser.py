"""Click an orbit in headless Chromium: a tap on a dashed (unstable) branch of the diagram's
overlay starts the scene views on that orbit. Helpers come from test_app_browser and
test_diagram_browser (same server fixture)."""
from conftest import RESULTS
from test_app_browser import open_app, query, snapshot, text
from test_diagram_browser import tap
from test_stability_browser import BRANCHES_READY

#: r = 0.6: the period-1 orbit is unstable beyond its period doubling at omega ~ 2.67.
QUERY = "?r=0.6&branches=1&bif_min=1.5&bif_max=3.5&bif_n=40"

#: A point of an unstable branch line near omega = 3 (the line's own data in the page).
UNSTABLE_POINT = """() => {
  const d = ie.data('branches_unstable');
  let best = null;
  for (let i = 0; i < d.xs.length; i++) {
    const xs = d.xs[i], ys = d.ys[i];
    for (let j = 0; j < xs.length; j++) {
      const off = Math.abs(xs[j] - 3.0);
      if (off < 0.1 && (best === null || off < best[2])) best = [xs[j], ys[j], off];
    }
  }
  return best;
}"""


def test_tap_on_an_unstable_branch_shows_its_orbit(page, server):
    open_app(page, server, QUERY)
    page.wait_for_function(BRANCHES_READY, timeout=120_000, polling=200)
    before = snapshot(page)
    x, y, _ = page.evaluate(UNSTABLE_POINT)
    tap(page, "bifurcation_figure", x, y)
    page.wait_for_function("() => location.search.includes('orbit_x0=')", timeout=10_000)
    q = query(page)
    x0, v0 = float(q["orbit_x0"]), float(q["orbit_v0"])
    # the Poincaré view (section at t = 0 mod T) starts on the orbit's state and its next
    # section point is the same state again (an orbit: to the URL's 10 digits times a
    # multiplier or two, within 1e-6)
    page.wait_for_function(
        "([x0, v0]) => { const d = ie.data('poincare'); return d.t.length > 1 && "
        "d.t[0] === 0 && Math.abs(d.x[0] - x0) < 1e-9 && Math.abs(d.v[0] - v0) < 1e-9; }",
        arg=[x0, v0], timeout=10_000, polling=100)
    first = page.evaluate("() => { const d = ie.data('poincare'); "
                          "return [d.x[1], d.v[1], d.x.length]; }")
    assert abs(first[0] - x0) < 1e-6 and abs(first[1] - v0) < 1e-6, (first, x0, v0)
    after = snapshot(page)
    assert after["phase"] != before["phase"] and after["imap"] != before["imap"]
    # the diagram was not computed again; its marker moved to the orbit's omega
    assert after["bif"] == before["bif"] and "complete" in after["bif_title"]
    assert abs(after["marker"] - float(q["omega"])) < 1e-12 and abs(after["marker"] - x) < 0.06
    page.wait_for_function("() => ie.data('branches_unstable').xs.length > 0", timeout=5_000)
    caption = text(page, "ie-caption")
    assert "orbit at ω" in caption and "periods" in caption, caption
    RESULTS.mkdir(exist_ok=True)
    page.screenshot(path=str(RESULTS / "orbit-click.png"))
