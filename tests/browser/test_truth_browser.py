"""The page never says what is not so (headless Chromium): a typed value is applied or
refused with a message and the box shows what is applied; the range boxes hold numbers;
the link and the history hold the page's state; the caption names what is on screen."""
import time

from playwright.sync_api import expect
from test_app_browser import open_app, open_settings, query, text

MARKER = "() => ie.model('bifurcation_marker').location"


def box(page, name):
    return page.locator(f".ie-w-{name} input").first


def type_into(page, name, value: str) -> None:
    b = box(page, name)
    b.fill(value)
    b.press("Enter")


def marker_at(page, value: float) -> None:
    page.wait_for_function(f"() => Math.abs(ie.model('bifurcation_marker').location - {value})"
                           " < 1e-9", timeout=15_000)


def caption_is(page, expected: str) -> None:
    deadline = time.monotonic() + 10
    while (now := text(page, "ie-caption")) != expected:
        assert time.monotonic() < deadline, now
        page.wait_for_timeout(100)


def message(page, *parts: str) -> str:
    """The message shown, once it holds every one of ``parts``."""
    page.locator(".ie-message").wait_for(state="visible", timeout=10_000)
    deadline = time.monotonic() + 10
    while not all(p in (msg := text(page, "ie-message")) for p in parts):
        assert time.monotonic() < deadline, msg
        page.wait_for_timeout(100)
    return msg


def test_typed_values_are_applied_or_refused_with_a_message(page, server):
    open_app(page, server, "?bif_n=40")
    # beyond the slider's teaching range, within the core's: applied, slider end moved
    type_into(page, "omega", "20")
    marker_at(page, 20)
    expect(box(page, "omega")).to_have_value("20.000", timeout=10_000)
    page.wait_for_function("() => location.search.includes('omega=20')", timeout=10_000)
    assert not page.locator(".ie-message").is_visible()
    # outside the core's range: refused, named with its value and range, box reverts
    for name, typed, shown, allowed in (("omega", "0", "20.000", "(0, 1000]"),
                                        ("omega", "1e6", "20.000", "(0, 1000]"),
                                        ("r", "1.5", "0.800", "[0, 1]")):
        type_into(page, name, typed)
        message(page, f"{name}: {float(typed):g} — ", allowed)
        expect(box(page, name)).to_have_value(shown, timeout=10_000)
        page.wait_for_timeout(300)
        assert page.evaluate(MARKER) == 20 and float(query(page)[name]) == float(shown)
    # a good value afterwards clears the message
    type_into(page, "c", "100")
    page.wait_for_function("() => location.search.includes('c=100')", timeout=10_000)
    page.locator(".ie-message").wait_for(state="hidden", timeout=10_000)
    expect(box(page, "c")).to_have_value("100.000", timeout=10_000)


def test_range_boxes_hold_numbers_after_a_switch_and_from_a_link(page, server):
    open_app(page, server, "?bif_param=r&bif_n=40")
    open_settings(page)
    page.get_by_text("Bifurcation diagram range", exact=True).click()
    expect(box(page, "bif_min")).to_have_value("0", timeout=10_000)
    expect(box(page, "bif_max")).to_have_value("1", timeout=10_000)
    for name, lo, hi in (("c", "0", "0.5"), ("g", "-1", "1"), ("omega", "0.1", "5")):
        page.locator(".ie-w-bif_param select").first.select_option(name)
        expect(box(page, "bif_min")).to_have_value(lo, timeout=10_000)
        expect(box(page, "bif_max")).to_have_value(hi, timeout=10_000)


def test_back_and_forward_restore_the_page(page, server):
    open_app(page, server, "?bif_n=40")
    type_into(page, "r", "0.75")
    page.wait_for_function("() => location.search.includes('r=0.75')", timeout=10_000)
    page.go_back()
    page.wait_for_function("() => !location.search.includes('r=0.75')", timeout=10_000)
    expect(box(page, "r")).to_have_value("0.800", timeout=30_000)
    page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0 && "
                           "Bokeh.documents[0].get_model_by_name('bifurcation_marker')",
                           timeout=30_000)
    page.go_forward()
    expect(box(page, "r")).to_have_value("0.750", timeout=30_000)
    assert query(page)["r"] == "0.75"


def test_a_scene_is_in_the_link_and_its_caption_survives_a_reload(page, server):
    open_app(page, server, "?bif_n=40")
    page.locator(".ie-scene select").select_option(label="Fig 2 · ω=2")   # same numbers
    page.wait_for_function("() => location.search === '?scene=fig2'", timeout=20_000)
    assert text(page, "ie-caption").startswith("Fig. 2, ω = 2")
    page.reload()
    open_app(page, server, "?" + page.url.split("?", 1)[1])
    assert text(page, "ie-caption").startswith("Fig. 2, ω = 2")
    expect(page.locator(".ie-scene select")).to_have_value("Fig 2 · ω=2")
    # a change: one line naming it; Reset: back to the scene
    type_into(page, "omega", "2.75")
    marker_at(page, 2.75)
    caption_is(page, "Fig. 2 with ω = 2.75")
    assert query(page) == {"scene": "fig2", "omega": "2.75"}    # the scene has 400 values
    expect(page.locator(".ie-scene select")).to_have_value("Fig 2 · ω=2")
    page.get_by_role("button", name="Reset").click()
    marker_at(page, 2)
    page.wait_for_function("() => location.search === '?scene=fig2'", timeout=10_000)
    assert text(page, "ie-caption").startswith("Fig. 2, ω = 2")


def test_one_bad_field_in_a_link_keeps_the_others(page, server):
    open_app(page, server, "?omega=2.5&r=5&c=0.1&bif_n=40")
    message(page, "r: 5 — ", "[0, 1]")
    assert page.evaluate(MARKER) == 2.5
    expect(box(page, "c")).to_have_value("0.100")
    expect(box(page, "r")).to_have_value("0.800")
    q = query(page)
    assert (q["omega"], q["r"], q["c"]) == ("2.5", "0.8", "0.1")


def test_display_toggles_leave_the_caption_alone(page, server):
    open_app(page, server, "?bif_n=40")
    type_into(page, "omega", "2.5")
    marker_at(page, 2.5)
    caption_is(page, "Paper defaults with ω = 2.5, bif_n = 40")
    page.locator(".ie-w-branches input").first.check()
    page.get_by_role("button", name="Presenter").click()
    page.wait_for_function("() => location.search.includes('presenter=1')", timeout=10_000)
    page.wait_for_function("() => location.search.includes('branches=1')", timeout=10_000)
    assert text(page, "ie-caption") == "Paper defaults with ω = 2.5, bif_n = 40"


def test_lyapunov_strip_counts_chaos_as_classify_does(page, server):
    """r = 1, c = 0 on 100 values of ω: the strip's chaos (title and red points) is
    classify's on the same grid, start and window, computed here."""
    import numpy as np

    import impactlib as il
    open_app(page, server, "?r=1&c=0&bif_n=100")
    page.wait_for_function("() => ie.title('lyapunov_figure').includes('chaotic')",
                           timeout=60_000)
    title = page.evaluate("ie.title('lyapunov_figure')")
    red = page.evaluate("() => { const d = ie.data('lyapunov'); "
                        "return d.omega.filter((w, i) => d.chaos[i]); }")
    positive = page.evaluate("() => ie.data('lyapunov').lyapunov.filter((l) => l > 0).length")
    p = il.Params(m=1.0, c=0.0, k=1.0, g=0.0, r=1.0, omega=2.0)
    grid = np.linspace(0.1, 5.0, 100)
    chaotic = [float(w) for w in grid
               if il.classify(il.simulate(p.replace(omega=float(w)), t_end=500.0,
                                          t_record=250.0)).kind == "chaotic"]
    assert sorted(red) == chaotic
    assert f"{len(chaotic)} of 100 values chaotic" in title, title
    assert positive > len(chaotic)


def test_scene_csvs_hold_the_start_and_psi_in_both_units(page, server):
    import math
    from pathlib import Path

    open_app(page, server, "?omega=2.8&psi=0.3&x0=0.25&v0=-0.5&bif_n=40")
    open_settings(page)
    page.get_by_text("Downloads", exact=True).click()
    for label in ("Impacts (CSV)", "Poincaré points (CSV)"):
        with page.expect_download(timeout=15_000) as info:
            page.get_by_text(label).click()
        lines = Path(info.value.path()).read_text().splitlines()
        head = dict(line[2:].split(" = ", 1) for line in lines if line.startswith("# "))
        assert (float(head["x0"]), float(head["v0"])) == (0.25, -0.5), head
        assert abs(float(head["psi"]) - 0.3) < 1e-9
        assert abs(float(head["psi_over_T"]) - 0.3 * 2.8 / (2 * math.pi)) < 1e-9


RANGES_HOLD_PINNED = """() => [['impact_map', 'phase', 'v'], ['poincare', 'x', 'v']].every(
  ([name, cx, cy]) => {
    const f = ie.model(name + '_figure'), d = ie.data(name + '_pinned');
    if (!d[cx].length) return false;
    return Math.min(...d[cx]) >= f.x_range.start && Math.max(...d[cx]) <= f.x_range.end &&
           Math.min(...d[cy]) >= f.y_range.start && Math.max(...d[cy]) <= f.y_range.end; })"""


def test_pinned_maps_stay_in_view_after_a_jump(page, server):
    open_app(page, server, "?bif_n=40")
    page.get_by_role("button", name="Pin maps").click()
    page.wait_for_function("() => ie.model('impact_map_pinned') && "
                           "ie.data('impact_map_pinned').v.length > 0", timeout=10_000)
    type_into(page, "omega", "0.2")                 # T ≈ 31 s, slow impacts
    marker_at(page, 0.2)
    page.wait_for_function("() => ie.title('impact_map_figure').includes('31.4')",
                           timeout=15_000)
    page.wait_for_function(RANGES_HOLD_PINNED, timeout=10_000)
