"""The diagram in any parameter, in headless Chromium: switching the swept parameter and
tapping the diagram. Helpers come from test_app_browser (same server fixture)."""
import re
import time

from test_app_browser import JS, READY, open_app, open_settings, query, text

#: Page position (CSS px) of data point (x, y) of a figure: the plot's view maps data to
#: canvas pixels; the canvas element's box places them on the page.
TO_PAGE = """([name, x, y]) => {
  const m = Bokeh.documents[0].get_model_by_name(name);
  const v = Bokeh.index.find_one_by_id(m.id);
  const r = v.canvas_view.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)];
}"""


def tap(page, figure: str, x: float, y: float) -> None:
    px, py = page.evaluate(TO_PAGE, [figure, x, y])
    page.mouse.click(px, py)


def diagram_ready(page, what: str) -> None:
    page.wait_for_function("() => ie.title('bifurcation_figure').includes('complete')",
                           timeout=30_000, polling=100)
    # the status pane's update may reach the page a message after the title's
    deadline = time.monotonic() + 10
    while not (status := text(page, "ie-diagram-status")).startswith("complete"):
        assert time.monotonic() < deadline, status
        page.wait_for_timeout(100)
    assert status.startswith("complete: " + what), status


def test_switching_bif_param_to_r_redraws_with_marker_at_r(page, server):
    open_app(page, server, "?r=0.7&bif_n=60")
    open_settings(page)
    page.get_by_text("Bifurcation diagram range", exact=True).click()
    page.locator(".ie-w-bif_param select").first.select_option("r")
    page.wait_for_function("() => ie.title('bifurcation_figure').includes('diagram in r')",
                           timeout=20_000)
    diagram_ready(page, "60 r values")
    state = page.evaluate("""() => {
      const f = ie.model('bifurcation_figure'); const x = ie.data('bifurcation').omega;
      return {marker: ie.model('bifurcation_marker').location, start: f.x_range.start,
              end: f.x_range.end, n: x.length, lo: Math.min(...x), hi: Math.max(...x),
              label: f.below[0].axis_label};
    }""")
    assert state["marker"] == 0.7
    assert (state["start"], state["end"]) == (0, 1)
    assert state["n"] > 0 and 0 <= state["lo"] and state["hi"] <= 1
    assert state["label"].startswith("restitution r")
    page.wait_for_function("() => location.search.includes('bif_param=r')", timeout=5_000)
    q = query(page)
    assert (float(q["bif_min"]), float(q["bif_max"])) == (0.0, 1.0)


def test_tap_on_the_diagram_moves_the_slider(page, server):
    open_app(page, server)
    tap(page, "bifurcation_figure", 3.0, -0.5)
    page.wait_for_function(
        "() => Math.abs(ie.model('bifurcation_marker').location - 3) < 0.05", timeout=10_000)
    step = (5.0 - 0.1) / 399
    omega = float(page.locator(".ie-w-omega input").first.input_value())
    assert abs(omega - 3.0) <= step + 0.01, omega
    page.wait_for_function("() => !location.search.includes('omega=2&')", timeout=5_000)
    assert abs(float(query(page)["omega"]) - 3.0) <= step + 0.01


def test_sweep_both_draws_up_and_down(page, server):
    page.goto(server.url + "?bif_sweep=both&bif_min=2.5&bif_max=2.8&bif_n=60")
    page.wait_for_function("() => window.Bokeh && Bokeh.documents.length && "
                           "Bokeh.documents[0].get_model_by_name('bifurcation_down')",
                           timeout=30_000)
    page.evaluate(JS)
    page.wait_for_function(
        "() => ie.len('bifurcation_up') > 0 && ie.len('bifurcation_down') > 0 &&"
        " ie.title('bifurcation_figure').includes('complete')", timeout=30_000)
    assert page.evaluate("ie.len('bifurcation')") == 0


def _dots_and_count(page) -> tuple[int, int]:
    """(dots in the diagram's source, distinct points its status line says it drew)."""
    status = text(page, "ie-diagram-status")
    m = re.search(r"(\d+) distinct points drawn", status)
    assert m, status
    return page.evaluate("ie.len('bifurcation')"), int(m.group(1))


def test_a_page_joining_a_diagram_under_way_draws_what_its_status_counts(page, server):
    """A second page opened while the first one's diagram streams (a link new to the
    server, so nothing is cached) follows the same computation: each page holds as many
    dots as its status line says, and both the same."""
    query_ = "?r=0.731&bif_n=2000"
    other = page.context.new_page()
    try:
        page.goto(server.url + query_)
        other.goto(server.url + query_)
        for p in (page, other):
            p.wait_for_function(READY, timeout=60_000, polling=100)
            p.evaluate(JS)
            diagram_ready(p, "2000 ω values")
        first, second = _dots_and_count(page), _dots_and_count(other)
    finally:
        other.close()
    assert first[0] == first[1] and second[0] == second[1]
    assert first == second
