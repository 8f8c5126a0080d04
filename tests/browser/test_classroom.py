"""The classroom page in headless Chromium: layout at projector, laptop and tablet sizes,
the animation (no server traffic while it plays), scene links, rounding, presenter
mode, taps, PNG export.

Geometry is read from the page (bounding boxes of the figures' elements); font sizes
from the Bokeh models (text is drawn on a canvas).
"""
import json
import re
import struct
import zlib
from pathlib import Path
from urllib.parse import parse_qs, urlparse

import pytest

from test_app_browser import JS, READY, close_settings, open_app, open_settings, text

RESULTS = Path(__file__).resolve().parents[2] / "test-results"
FIGURES = ("displacement_figure", "phase_figure", "impact_map_figure", "poincare_figure",
           "bifurcation_figure", "animation_figure")

BOXES = """(names) => {
  const doc = Bokeh.documents[0];
  const out = {};
  for (const n of names) {
    const v = Bokeh.index.find_one(doc.get_model_by_name(n));
    const b = v.el.getBoundingClientRect();
    out[n] = {left: b.left, top: b.top, right: b.right, bottom: b.bottom,
              width: b.width, height: b.height};
  }
  return out;
}"""
#: Is the centre of each figure showing that figure (nothing drawn over it)?
CENTRE_VISIBLE = """(names) => {
  const doc = Bokeh.documents[0];
  function deepest(x, y) {
    let e = document.elementFromPoint(x, y);
    while (e && e.shadowRoot) {
      const inner = e.shadowRoot.elementFromPoint(x, y);
      if (!inner || inner === e) break;
      e = inner;
    }
    return e;
  }
  function inside(e, target) {
    for (; e; e = e.parentNode || e.host) if (e === target) return true;
    return false;
  }
  const out = {};
  for (const n of names) {
    const v = Bokeh.index.find_one(doc.get_model_by_name(n));
    const b = v.el.getBoundingClientRect();
    out[n] = inside(deepest((b.left + b.right) / 2, (b.top + b.bottom) / 2), v.el);
  }
  return out;
}"""


def goto(page, server, query="", size=(1280, 720)):
    page.set_viewport_size({"width": size[0], "height": size[1]})
    open_app(page, server, query)


def overlap(a, b) -> bool:
    return (min(a["right"], b["right"]) - max(a["left"], b["left"]) > 0.5 and
            min(a["bottom"], b["bottom"]) - max(a["top"], b["top"]) > 0.5)


@pytest.mark.parametrize("size,fits", [((1280, 720), True), ((1920, 1080), True),
                                       ((768, 1024), False), ((853, 480), False)])
def test_every_figure_is_laid_out_without_overlap(page, server, size, fits):
    """Projector sizes: all six figures inside the window at once (page at the top), at
    least 120 x 80, centres visible. Tablet and 150 % zoom: inside the width (scrolling
    down allowed). Never two overlapping, never a sideways scroll."""
    goto(page, server, size=size)
    page.wait_for_timeout(500)             # let the grid settle after the data arrived
    w, h = size
    boxes = page.evaluate(BOXES, list(FIGURES))
    for n, b in boxes.items():
        assert b["left"] >= -0.5 and b["right"] <= w + 0.5, (n, b)
        assert b["width"] >= 120 and b["height"] >= 80, (n, b)
        if fits:
            assert b["top"] >= -0.5 and b["bottom"] <= h + 0.5, (n, b)
    for i, a in enumerate(FIGURES):
        for b in FIGURES[i + 1:]:
            assert not overlap(boxes[a], boxes[b]), (a, b, boxes[a], boxes[b])
    assert page.evaluate("document.documentElement.scrollWidth") <= w
    if fits:
        assert page.evaluate("document.documentElement.scrollHeight") <= h
        assert all(page.evaluate(CENTRE_VISIBLE, list(FIGURES)).values())
    page.screenshot(path=str(RESULTS / f"layout-{w}x{h}.png"))


def test_the_settings_drawer_opens_over_the_plots(page, server):
    """The drawer overlays the page: opening it moves or resizes no figure."""
    goto(page, server, size=(1280, 720))
    before = page.evaluate(BOXES, list(FIGURES))
    open_settings(page)
    assert page.locator(".ie-w-m input").first.is_visible()
    page.wait_for_timeout(300)
    assert page.evaluate(BOXES, list(FIGURES)) == before
    close_settings(page)


MASS_X = "() => ie.data('animation_mass').x[0]"
PLAY = ".ie-anim-play button"


def test_play_moves_the_mass_with_no_message_from_the_server(page, server):
    """While the animation plays for a second, no websocket frame arrives from the
    server (nor leaves for it); pause stops the mass."""
    frames = {"in": 0, "out": 0}

    def on_ws(ws):
        ws.on("framereceived", lambda payload: frames.__setitem__("in", frames["in"] + 1))
        ws.on("framesent", lambda payload: frames.__setitem__("out", frames["out"] + 1))
    page.on("websocket", on_ws)
    goto(page, server, size=(1280, 720))
    page.wait_for_timeout(1000)              # the diagram's last messages have arrived
    page.locator(PLAY).click()
    page.wait_for_timeout(150)               # the click's own frame has been drawn
    NOW = "() => [ie.data('animation_mass').t[0], performance.now() / 1000]"
    x0 = page.evaluate(MASS_X)
    t0, wall0 = page.evaluate(NOW)
    seen = dict(frames)
    positions = []
    for _ in range(10):
        page.wait_for_timeout(100)
        positions.append(page.evaluate(MASS_X))
    t1, wall1 = page.evaluate(NOW)
    assert frames == seen, f"websocket frames while playing: {frames} vs {seen}"
    assert len(set(positions + [x0])) > 5, positions          # it moves, frame by frame
    # 1x: one simulated second per second (give or take two frames at 30 fps)
    assert abs((t1 - t0) - (wall1 - wall0)) < 0.1, (t1 - t0, wall1 - wall0)
    cursor = page.evaluate("() => ie.data('displacement_cursor').t[0]")
    assert abs(cursor - t1) < 0.2
    page.locator(PLAY).click()               # pause
    page.wait_for_timeout(100)
    x_paused = page.evaluate(MASS_X)
    page.wait_for_timeout(500)
    assert page.evaluate(MASS_X) == x_paused
    t_paused = page.evaluate("() => ie.data('animation_mass').t[0]")
    page.locator(".ie-anim-step button").click()         # one frame at 1x: 1/30 s
    page.wait_for_function(f"() => ie.data('animation_mass').t[0] > {t_paused}", timeout=2_000)
    assert page.evaluate("() => ie.data('animation_mass').t[0]") - t_paused == \
        pytest.approx(1 / 30, rel=1e-6)


def test_fig4_animation_rests_on_the_wall_while_sticking(page, server):
    """Fig. 4 (complete chattering): seeking into a sticking interval puts the mass on
    the wall (x = g) at rest, marked yellow; seeking into flight lifts it off."""
    goto(page, server, "?scene=fig4", size=(1280, 720))
    page.wait_for_function("() => ie.len('displacement_sticking') > 0", timeout=10_000)
    start, end, following = page.evaluate("""() => { const d = ie.data('displacement_sticking');
        const i = Math.max(0, d.start.length - 2);
        return [d.start[i], d.end[i], d.start[i + 1] || d.end[i] + 30]; }""")
    seek = """(t) => { const s = ie.model('animation_time'); s.value = t; }"""
    page.locator(PLAY).click()
    page.locator(PLAY).click()
    page.evaluate(seek, (start + end) / 2)
    page.wait_for_timeout(100)
    state = page.evaluate("() => [ie.data('animation_mass').x[0], ie.data('animation_mass').v[0]]")
    assert state == [0.0, 0.0], state
    color = page.evaluate("""() => Bokeh.documents[0].get_model_by_name('animation_mass')
                              .glyph.fill_color""")
    assert "f2b134" in json.dumps(color).lower()
    # between the release and the next sticking interval the mass flies off the wall
    heights = []
    for k in range(1, 12):
        page.evaluate(seek, end + (following - end) * k / 12)
        heights.append(page.evaluate(MASS_X))
    assert max(heights) > 0.05 and min(heights) >= 0.0, heights
    page.evaluate(seek, start - 0.5)
    page.wait_for_timeout(100)
    RESULTS.mkdir(exist_ok=True)
    page.screenshot(path=str(RESULTS / "animation-fig4.png"))


def query(page) -> dict:
    return {k: v[-1] for k, v in parse_qs(urlparse(page.url).query).items()}


def test_scene_link_restores_settings_and_caption(page, server):
    goto(page, server, "?scene=fig5")
    assert page.evaluate("ie.model('bifurcation_marker').location") == 1.2
    assert "window [2500, 3000] s" in page.evaluate("ie.title('bifurcation_figure')")
    assert text(page, "ie-caption").startswith("Fig. 5")
    assert "changed" not in text(page, "ie-caption")
    page.wait_for_function("() => location.search.includes('scene=fig5')", timeout=5_000)
    # numbers given in the link override the scene's
    goto(page, server, "?scene=fig5&omega=1.25")
    assert page.evaluate("ie.model('bifurcation_marker').location") == 1.25
    assert "window [2500, 3000] s" in page.evaluate("ie.title('bifurcation_figure')")
    assert text(page, "ie-caption") == "Fig. 5 with ω = 1.25"


#: The scene's data (the displacement line is sampled for the screen's width, so it is
#: left out: the phase trajectory holds the scene's own samples).
SUMS = """() => ({phase: ie.sum('phase', 'x'), imap: ie.sum('impact_map', 'v'),
                  poinc: ie.sum('poincare', 'x'), n: ie.len('phase')})"""


def significant_digits(text: str) -> int:
    mantissa = text.lower().split("e")[0].lstrip("+-").replace(".", "").lstrip("0")
    return len(mantissa.rstrip("0")) if "." in text.split("e")[0] else len(mantissa)


def test_link_written_by_the_app_is_short_and_reproduces_the_scene(page, server):
    """A value off the step grid, as a slider or a typed box sends it, is computed on
    the grid; the URL holds at most 10 significant digits and gives the same data in a
    new page, also at the chaotic ω = 2.81."""
    goto(page, server)
    box = page.locator(".ie-w-omega input").first
    box.fill("2.8099999999999996")
    box.press("Enter")
    page.wait_for_function("() => Math.abs(ie.model('bifurcation_marker').location - 2.81) < 1e-12",
                           timeout=10_000)
    page.wait_for_function("() => location.search.includes('omega=2.81&')", timeout=5_000)
    q = query(page)
    for name, value in q.items():
        if re.fullmatch(r"[-+0-9.eE]+", value):
            assert significant_digits(value) <= 10, (name, value)
    assert q["omega"] == "2.81"
    page.wait_for_timeout(300)
    first = page.evaluate(SUMS)
    url = page.url
    page.goto(url)
    page.wait_for_function(READY, timeout=30_000, polling=100)
    page.evaluate(JS)
    assert page.evaluate("ie.model('bifurcation_marker').location") == 2.81
    assert page.evaluate(SUMS) == first


def phase_pixel(page, x, v):
    """Page coordinates of the data point (x, v) of the phase figure."""
    return page.evaluate("""([x, v]) => {
        const fig = Bokeh.documents[0].get_model_by_name('phase_figure');
        const view = Bokeh.index.find_one(fig);
        const b = view.el.getBoundingClientRect();
        return [b.left + view.frame.x_scale.compute(x), b.top + view.frame.y_scale.compute(v)];
    }""", [x, v])


def test_tap_on_the_phase_plane_sets_the_initial_state(page, server):
    goto(page, server, size=(1280, 720))
    x_lo, x_hi, v_lo, v_hi = page.evaluate("""() => {
        const f = ie.model('phase_figure');
        return [f.x_range.start, f.x_range.end, f.y_range.start, f.y_range.end]; }""")
    px, py = phase_pixel(page, 1.0, 0.5)
    page.mouse.click(px, py)
    x_box, v_box = page.locator(".ie-w-x0 input").first, page.locator(".ie-w-v0 input").first
    page.wait_for_function("""() => new URLSearchParams(location.search).has('x0')""",
                           timeout=10_000)
    # one pixel of the figure in data units
    fig_px = page.evaluate(BOXES, ["phase_figure"])["phase_figure"]
    tol_x = 2 * (x_hi - x_lo) / fig_px["width"]
    tol_v = 2 * (v_hi - v_lo) / fig_px["height"]
    q = query(page)
    assert abs(float(q["x0"]) - 1.0) < tol_x and abs(float(q["v0"]) - 0.5) < tol_v, q
    open_settings(page)
    page.get_by_text("Time window, start, method").click()    # built when first opened
    assert abs(float(x_box.input_value()) - 1.0) < tol_x
    assert abs(float(v_box.input_value()) - 0.5) < tol_v
    close_settings(page)
    # below the wall (x < g = 0): the motion starts on the wall
    x_lo = page.evaluate("() => ie.model('phase_figure').x_range.start")
    assert x_lo < 0
    px, py = phase_pixel(page, x_lo / 2, -0.3)
    page.mouse.click(px, py)
    page.wait_for_function("""() => new URLSearchParams(location.search).get('x0') === '0.0'""",
                           timeout=10_000)
    assert abs(float(query(page)["v0"]) + 0.3) < tol_v


def font_px(size) -> float:
    size = size if isinstance(size, str) else size["value"]
    return float(re.match(r"([0-9.]+)px", size).group(1))


FONTS = """(names) => names.map((n) => {
    const f = Bokeh.documents[0].get_model_by_name(n);
    const axes = [...f.below, ...f.left].filter((a) => a.major_label_text_font_size);
    return [n, f.title.text_font_size, axes.map((a) => a.major_label_text_font_size)];
})"""


def test_presenter_mode_uses_large_type(page, server):
    goto(page, server, "?presenter=1", size=(1920, 1080))
    for name, title, ticks in page.evaluate(FONTS, list(FIGURES)):
        assert font_px(title) >= 22, (name, title)
        assert ticks and all(font_px(t) >= 18 for t in ticks), (name, ticks)
    assert query(page).get("presenter") == "1"
    RESULTS.mkdir(exist_ok=True)
    page.screenshot(path=str(RESULTS / "presenter-1920x1080.png"))
    page.locator(".ie-w-presenter button").click()      # the toggle turns it off
    page.wait_for_function("""() => { const f = ie.model('phase_figure');
        return f.title.text_font_size === '14px'; }""", timeout=20_000)
    page.wait_for_function("() => !location.search.includes('presenter')", timeout=5_000)


def png_size(data: bytes) -> tuple[int, int]:
    """Width and height of a PNG, after checking its signature and that its image data
    inflates to exactly what the header says (8-bit RGB or RGBA)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        assert zlib.crc32(kind + body) == struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])[0]
        if kind == b"IHDR":
            width, height, depth, color = struct.unpack(">IIBB", body[:10])
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    channels = {2: 3, 6: 4}[color]
    assert depth == 8 and len(zlib.decompress(idat)) == height * (1 + width * channels)
    return width, height


def test_png_export_is_one_image_of_all_views(page, server, tmp_path):
    goto(page, server, size=(1280, 720))
    with page.expect_download(timeout=15_000) as info:
        page.locator(".ie-png button").click()
    path = tmp_path / "page.png"
    info.value.save_as(path)
    data = path.read_bytes()
    width, height = png_size(data)
    assert (width, height) == (1600, 900)
    from PIL import Image
    img = Image.open(path).convert("RGB")
    # the six figures, each where the export drew it (tests/browser/test_modes.py checks
    # that layout against a real window): sample each one's region
    boxes = page.evaluate("window.__iePngLayout.frames")
    assert set(FIGURES) <= set(boxes), sorted(boxes)
    for n in FIGURES:
        x, y, w, h = boxes[n]["box"]
        colours = img.crop((int(x), int(y), int(x + w), int(y + h))).getcolors(maxcolors=1_000_000)
        assert colours is not None and len(colours) > 20, n     # drawn, not blank
