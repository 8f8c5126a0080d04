"""The page's modes at a projector, a monitor, a tablet and a phone, in headless Chromium.

Sizes are Bokeh's inner frames (the data area) read from the page. The minimums are the
classroom page's: at 1280 x 720 the diagram at least 560 x 200, each scene view 220 x 140,
the animation 280 x 90, no page scroll; at 1920 x 1080 the diagram 900 x 300 and each
scene view 360 x 220; research at 1280 x 720 the regime map and the basins 700 x 420 with
their legend inside the window; presenter mode no data area under 90 % of the same
view's in normal mode. Screenshots of every mode at the four sizes go to
docs/screenshots/ (shown in the README).
"""
from pathlib import Path

import pytest
from fontTools.ttLib import TTFont

from test_app_browser import JS, READY
from test_research_browser import FILLED, wait_complete

ROOT = Path(__file__).resolve().parents[2]
SHOTS = ROOT / "test-results" / "modes"
SIZES = {"projector": (1280, 720), "monitor": (1920, 1080), "tablet": (768, 1024),
         "phone": (390, 844)}
SCENE_VIEWS = ("displacement_figure", "phase_figure", "impact_map_figure", "poincare_figure")
EXPLORE = SCENE_VIEWS + ("animation_figure", "bifurcation_figure", "lyapunov_figure")
#: (width, height) minimum of the data areas, by window size; None: no minimum there.
MINIMUM = {
    (1280, 720): {"bifurcation_figure": (560, 200), "animation_figure": (280, 90),
                  **{n: (220, 140) for n in SCENE_VIEWS}},
    (1920, 1080): {"bifurcation_figure": (900, 300), **{n: (360, 220) for n in SCENE_VIEWS}},
}
#: Bokeh models the page may hold (BokehJS's count, ``all_models``): the first page
#: (explore) and after opening each other mode. The classroom page's target for the first
#: page is 140; what is left above it is seven figures' own models (about 20 each).
MODEL_BUDGET = {"explore": 182, "compare": 287, "research": 248}
#: Fonts a stock Debian Chromium has for any text (fonts-dejavu-core); the page ships none.
DEJAVU = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"

#: Frame (data area) and element box of every figure shown, by name.
FRAMES = """() => {
  const out = {};
  for (const v of Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")) {
    const b = v.el.getBoundingClientRect();
    if (b.width === 0 || b.height === 0) continue;
    const f = v.frame.bbox;
    out[v.model.name] = {w: f.width, h: f.height, left: b.left + f.left, top: b.top + f.top,
                         right: b.left + f.right, bottom: b.top + f.bottom,
                         box: [b.left, b.top, b.right, b.bottom]};
  }
  return out;
}"""
#: Title or x axis label wider than its frame (drawn clipped): [name, text width, frame
#: width].
CLIPPED = """() => {
  const ctx = document.createElement("canvas").getContext("2d");
  const out = [];
  for (const v of Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")) {
    const t = v.model.title;
    if (!t || !t.text || v.el.getBoundingClientRect().width === 0) continue;
    const size = typeof t.text_font_size === "string" ? t.text_font_size : t.text_font_size.value;
    ctx.font = `${t.text_font_style} ${size} ${t.text_font}`;
    const w = ctx.measureText(t.text).width;
    if (w > v.frame.bbox.width + 0.5) out.push([v.model.name, w, v.frame.bbox.width]);
    for (const a of v.model.below) {
      if (typeof a.axis_label !== "string" || !a.axis_label) continue;
      const s = a.axis_label_text_font_size;
      ctx.font = `${a.axis_label_text_font_style} ${typeof s === "string" ? s : s.value} ${a.axis_label_text_font}`;
      const wl = ctx.measureText(a.axis_label).width;
      if (wl > v.frame.bbox.width + 0.5) out.push([v.model.name + " x label", wl, v.frame.bbox.width]);
    }
  }
  return out;
}"""
#: Every character of the page's text: the DOM's (through shadow roots) and the text
#: BokehJS draws on canvases (titles, axis labels, labels, tick labels are ASCII digits).
PAGE_TEXT = """() => {
  const parts = [];
  const walk = (root) => {
    for (const e of root.querySelectorAll("*")) {
      if (e.shadowRoot) walk(e.shadowRoot);
      if (["STYLE", "SCRIPT", "LINK"].includes(e.tagName)) continue;
      for (const n of e.childNodes) if (n.nodeType === 3) parts.push(n.textContent);
      if (e.tagName === "OPTION") parts.push(e.label);
    }
  };
  walk(document);
  for (const m of Bokeh.documents[0].all_models) {
    for (const k of ["text", "axis_label", "label"]) {
      const v = m.properties[k] ? m[k] : null;
      if (typeof v === "string") parts.push(v);
    }
  }
  return parts.join(" ");
}"""


#: The Lyapunov strip's y axis: [smallest gap between two tick labels (px), label font
#: size (px), number of ticks].
STRIP_TICKS = """() => {
  const v = Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")
    .find((v) => v.model.name === "lyapunov_figure");
  const ax = v.axis_views.find((a) => a.dimension === 1);
  const ys = [...ax.tick_coords.major[1]].sort((a, b) => a - b);
  const r = v.model.y_range, h = v.frame.bbox.height;
  const gaps = ys.slice(1).map((y, i) => (y - ys[i]) * h / Math.abs(r.end - r.start));
  const f = ax.model.major_label_text_font_size;
  return [Math.min(...gaps), parseFloat(typeof f === "string" ? f : f.value), ys.length];
}"""
#: Compare mode's last diagram and last section hold data.
COMPARE_FILLED = """() => { const d = Bokeh.documents[0];
    return ['compare_fig3f', 'compare_fig7d'].every((n) => {
      const f = d.get_model_by_name(n);
      return f && f.renderers[0].data_source.data[Object.keys(f.renderers[0].data_source.data)[0]].length > 0; }); }"""


def open_page(page, server, size, query=""):
    page.set_viewport_size({"width": size[0], "height": size[1]})
    page.goto(server.url + query)
    page.wait_for_function(READY, timeout=60_000, polling=100)
    page.evaluate(JS)
    page.wait_for_timeout(1200)          # titles fitted, the grid settled


def show_mode(page, label: str):
    page.locator(".ie-w-mode button", has_text=label).click()


def overlap(a, b) -> bool:
    (al, at, ar, ab), (bl, bt, br, bb) = a["box"], b["box"]
    return min(ar, br) - max(al, bl) > 0.5 and min(ab, bb) - max(at, bt) > 0.5


def check_layout(page, size, names, scrolls: bool) -> dict:
    """Every figure in ``names`` shown; none overlapping another; no sideways scroll;
    no clipped title or x axis label (drawn no wider than its frame); with ``scrolls`` False,
    everything inside the window."""
    w, h = size
    frames = page.evaluate(FRAMES)
    missing = [n for n in names if n not in frames]
    assert not missing, (missing, sorted(frames))
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            assert not overlap(frames[a], frames[b]), (a, b, frames[a], frames[b])
        assert frames[a]["box"][0] >= -0.5 and frames[a]["box"][2] <= w + 0.5, (a, frames[a])
    assert page.evaluate("document.documentElement.scrollWidth") <= w
    if not scrolls:
        assert page.evaluate("document.documentElement.scrollHeight") <= h
        for n in names:
            assert frames[n]["box"][3] <= h + 0.5, (n, frames[n])
    assert page.evaluate(CLIPPED) == []
    return frames


def assert_strip_ticks_apart(page):
    """The strip's tick labels do not overlap: at least a label's height (its font size)
    apart."""
    gap, font, n = page.evaluate(STRIP_TICKS)
    assert n >= 2 and gap >= font, (gap, font, n)


def assert_minimum(frames, size):
    for name, (w, h) in MINIMUM.get(size, {}).items():
        f = frames[name]
        assert f["w"] >= w and f["h"] >= h, (name, size, round(f["w"]), round(f["h"]))


@pytest.mark.parametrize("where", list(SIZES))
def test_explore_sizes_and_presenter(page, server, where):
    """Explore at the four sizes (minimum data areas, no overlap, no sideways scroll, no
    clipped title), then in presenter mode (the same checks; from 900 px wide it keeps
    90 % of every data area)."""
    size = SIZES[where]
    open_page(page, server, size)
    fits = size[0] >= 900
    normal = check_layout(page, size, EXPLORE, scrolls=not fits)
    assert_minimum(normal, size)
    assert_strip_ticks_apart(page)
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / f"explore-{where}.png"))
    page.locator(".ie-w-presenter button").click()
    page.wait_for_function("() => ie.model('phase_figure').title.text_font_size !== '14px'",
                           timeout=20_000)
    page.wait_for_timeout(1200)
    big = check_layout(page, size, EXPLORE, scrolls=not fits)
    assert_strip_ticks_apart(page)
    if not fits:                    # a tablet or phone: one scrolling column, titles fit
        return
    for n in EXPLORE:
        assert big[n]["w"] >= 0.9 * normal[n]["w"] and big[n]["h"] >= 0.9 * normal[n]["h"], \
            (n, big[n], normal[n])
    page.screenshot(path=str(SHOTS / f"presenter-{where}.png"))


@pytest.mark.parametrize("where", list(SIZES))
def test_compare_fills_its_room(page, server, where):
    size = SIZES[where]
    open_page(page, server, size)
    show_mode(page, "Compare")
    names = tuple(f"compare_fig3{c}" for c in "abcdef") + tuple(f"compare_fig7{c}" for c in "abcd")
    page.wait_for_function(COMPARE_FILLED, timeout=90_000)
    page.wait_for_timeout(800)
    frames = check_layout(page, size, names, scrolls=size[0] < 900)
    assert all(frames[n]["box"][1] > 0 for n in names)        # below the header
    for n in SCENE_VIEWS:                                      # explore gave up its room
        assert n not in frames, n
    page.screenshot(path=str(SHOTS / f"compare-{where}.png"))


def test_compare_from_a_link_is_laid_out_as_when_switched_to(page, server):
    """At 1280 x 720, ``?mode=compare`` (the page built with the mode open) gives the
    small multiples the same frames as a click on Compare after load: no page scroll."""
    size = SIZES["projector"]
    names = tuple(f"compare_fig3{c}" for c in "abcdef") + tuple(f"compare_fig7{c}" for c in "abcd")
    frames = {}
    for how in ("link", "switch"):
        open_page(page, server, size, "?mode=compare" if how == "link" else "")
        if how == "switch":
            show_mode(page, "Compare")
        page.wait_for_function(COMPARE_FILLED, timeout=90_000)
        page.wait_for_timeout(800)
        frames[how] = check_layout(page, size, names, scrolls=False)
    for n in names:
        link, switch = frames["link"][n], frames["switch"][n]
        assert abs(link["w"] - switch["w"]) <= 1 and abs(link["h"] - switch["h"]) <= 1, (n, link, switch)


@pytest.mark.parametrize("where", list(SIZES))
def test_research_owns_the_plot_area(page, server, where):
    size = SIZES[where]
    open_page(page, server, size, "?omega=2.62")
    show_mode(page, "Research")
    page.wait_for_function(FILLED, arg="regime_map", timeout=90_000)
    wait_complete(page, "ie-map-status", timeout=90)
    page.wait_for_timeout(500)
    frames = check_layout(page, size, ("regime_map_figure",), scrolls=size[0] < 900)
    legend = page.locator(".ie-map-legend").first.bounding_box()
    if size[0] >= 900:
        f = frames["regime_map_figure"]
        if size == (1280, 720):
            assert f["w"] >= 700 and f["h"] >= 420, f
        assert legend["y"] + legend["height"] <= size[1] + 0.5, legend
        assert legend["x"] + legend["width"] <= size[0] + 0.5, legend
    page.screenshot(path=str(SHOTS / f"research-{where}.png"))
    page.locator(".bk-tab", has_text="Basins").first.click()
    page.wait_for_function(FILLED, arg="basins", timeout=90_000)
    wait_complete(page, "ie-basins-status", timeout=90)
    page.wait_for_timeout(500)
    frames = check_layout(page, size, ("basins_figure",), scrolls=size[0] < 900)
    if size == (1280, 720):
        f = frames["basins_figure"]
        assert f["w"] >= 700 and f["h"] >= 420, f
    # a setting changed since the pictures were made: the note in their titles fits too
    box = page.locator(".ie-w-c input").first
    box.fill("0.1")
    box.press("Enter")
    for name, tab in (("basins_figure", None), ("regime_map_figure", "Regime map")):
        if tab:
            page.locator(".bk-tab", has_text=tab).first.click()
        page.wait_for_function(f"() => ie.title('{name}').includes('settings changed')",
                               timeout=20_000)
        page.wait_for_timeout(1200)         # titles fitted
        check_layout(page, size, (name,), scrolls=size[0] < 900)


def test_tablet_has_omega_and_two_scene_views_on_screen(page, server):
    """768 x 1024 at load: ω's box and two scene views inside the window, uncovered."""
    open_page(page, server, (768, 1024))
    box = page.locator(".ie-w-omega input").first.bounding_box()
    assert box["y"] >= 0 and box["y"] + box["height"] <= 1024
    frames = page.evaluate(FRAMES)
    seen = [n for n in SCENE_VIEWS if frames[n]["box"][3] <= 1024]
    assert len(seen) >= 2, frames
    # the sticky top (header and bar) does not cover them: their centres are theirs
    for n in seen:
        l, t, r, b = frames[n]["box"]
        owner = page.evaluate("""([x, y, name]) => {
            let e = document.elementFromPoint(x, y);
            while (e && e.shadowRoot) { const i = e.shadowRoot.elementFromPoint(x, y);
                                        if (!i || i === e) break; e = i; }
            const el = Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name(name)).el;
            for (; e; e = e.parentNode || e.host) if (e === el) return true;
            return false; }""", [(l + r) / 2, (t + b) / 2, n])
        assert owner, n


def test_omega_is_reached_within_five_tab_presses(page, server):
    open_page(page, server, (1280, 720))
    page.evaluate("() => document.activeElement && document.activeElement.blur()")
    for presses in range(1, 6):
        page.keyboard.press("Tab")
        inside = page.evaluate("""() => { let e = document.activeElement;
            while (e && e.shadowRoot && e.shadowRoot.activeElement) e = e.shadowRoot.activeElement;
            for (; e; e = e.parentNode || e.host)
              if (e.classList && e.classList.contains('ie-w-omega')) return e.tagName; return null; }""")
        if inside:
            break
    assert inside, "ω's box is not among the first five Tab stops"


def test_every_character_is_in_a_font_the_page_can_count_on(page, server):
    """Each non-ASCII character of the page's text (HTML and what Bokeh draws) is in
    DejaVu Sans, which every Debian Chromium has; the page ships no font of its own."""
    cmap = TTFont(DEJAVU).getBestCmap()
    missing = {}
    for query, mode in (("", None), ("?scene=fig4", None), ("?omega=banana", None),
                        ("", "Compare"), ("", "Research")):
        open_page(page, server, (1280, 720), query)
        if mode:
            show_mode(page, mode)
            page.wait_for_timeout(3000)
        page.locator(".ie-sidebar-toggle button").click()        # the drawer's cards
        page.wait_for_timeout(300)
        text = page.evaluate(PAGE_TEXT)
        for ch in set(text):
            if ord(ch) > 127 and not ch.isspace() and ord(ch) not in cmap:
                missing.setdefault(ch, query or mode)
    assert not missing, {f"U+{ord(c):04X} {c}": where for c, where in missing.items()}


def test_model_count_of_each_mode(page, server):
    """A count, not a timing: every model is built, sent and drawn per session. Each
    mode is opened in a page of its own (the first page is explore)."""
    counts = {}
    for mode in ("Explore", "Compare", "Research"):
        open_page(page, server, (1280, 720))
        if mode != "Explore":
            show_mode(page, mode)
            page.wait_for_timeout(2500)
        counts[mode.lower()] = page.evaluate("Bokeh.documents[0].all_models.size")
    over = {m: n for m, n in counts.items() if n > MODEL_BUDGET[m]}
    assert not over, (counts, MODEL_BUDGET)


def test_a_phone_lays_the_page_out_at_its_own_width(browser, server):
    """A phone (390 x 844, mobile viewport) lays the page out 390 px wide, not 980 px
    zoomed out: no sideways scroll and ω's box on screen. The same context shows a page
    without a viewport tag at 980 px, so the emulation is a phone's."""
    context = browser.new_context(viewport={"width": 390, "height": 844}, is_mobile=True,
                                  has_touch=True, device_scale_factor=3)
    try:
        page = context.new_page()
        page.set_content("<html><head></head><body><p>no viewport tag</p></body></html>")
        assert page.evaluate("document.documentElement.clientWidth") == 980
        page.goto(server.url)
        page.wait_for_function(READY, timeout=60_000, polling=100)
        page.wait_for_timeout(1200)
        assert page.evaluate("document.documentElement.clientWidth") == 390
        assert page.evaluate("document.documentElement.scrollWidth") <= 390
        box = page.locator(".ie-w-omega input").first.bounding_box()
        assert box["x"] >= 0 and box["x"] + box["width"] <= 390, box
        assert box["y"] >= 0 and box["y"] + box["height"] <= 844, box
    finally:
        context.close()


def save_png(page, tmp_path, name):
    with page.expect_download(timeout=30_000) as info:
        page.locator(".ie-png button").click()
    path = tmp_path / name
    info.value.save_as(path)
    return path, page.evaluate("window.__iePngLayout")


@pytest.mark.parametrize("mode", ["Explore", "Research"])
def test_png_is_the_mode_laid_out_for_1600_by_900_whatever_the_window(page, server, tmp_path,
                                                                      mode):
    """Save PNG at a projector's and at a phone's window gives a 1600 x 900 image of the
    plot area whose figures have the data areas of a real window 1600 px wide whose plot
    area is 900 px high (the header's height added, as the export reports it), each
    drawn (not blank) where the export put it; the page gets its own layout back."""
    from PIL import Image

    from test_classroom import png_size

    def show(size):
        open_page(page, server, size, "?omega=2.62")
        if mode == "Research":
            show_mode(page, mode)
            page.wait_for_function(FILLED, arg="regime_map", timeout=90_000)
            wait_complete(page, "ie-map-status", timeout=90)
            page.wait_for_timeout(800)
        return page.evaluate(FRAMES)

    wide = None
    for size in ((1280, 720), (390, 844)):
        before = show(size)
        path, layout = save_png(page, tmp_path, f"{mode}-{size[0]}.png")
        page.wait_for_timeout(1500)
        after = page.evaluate(FRAMES)
        for name, f in before.items():          # the page's own layout is back
            assert abs(after[name]["w"] - f["w"]) <= 1 and abs(after[name]["h"] - f["h"]) <= 1, \
                (name, size, f, after[name])
        if wide is None:
            assert 0 < layout["top"] < 200, layout
            wide = show((1600, round(900 + layout["top"])))
        assert png_size(path.read_bytes()) == (1600, 900) == tuple(layout["size"])
        assert set(layout["frames"]) == set(wide), (sorted(layout["frames"]), sorted(wide))
        img = Image.open(path).convert("RGB")
        for name, got in layout["frames"].items():
            w, h = got["frame"]
            assert abs(w - wide[name]["w"]) <= 2 and abs(h - wide[name]["h"]) <= 2, \
                (name, size, got, wide[name])
            x, y, bw, bh = got["box"]
            assert x >= -0.5 and y >= -0.5 and x + bw <= 1600.5 and y + bh <= 900.5, (name, got)
            colours = img.crop((int(x), int(y), int(x + bw), int(y + bh))).getcolors(1_000_000)
            assert colours is not None and len(colours) > 20, name      # drawn, not blank
