"""Screenshots of the served app for the README (docs/screenshots/).

    panel serve app/app.py --port 5006 &
    .venv/bin/python scripts/screenshots.py http://127.0.0.1:5006/app

Takes each mode (explore, presenter, compare, research) at 1280 x 720 (a projector),
1920 x 1080 (a monitor), 768 x 1024 (a tablet) and 390 x 844 (a phone), as the window
shows it, and the Fig. 4 animation while the mass chatters on the wall. Each PNG is
reduced to a 256-colour palette to keep the repository small. The phone's pictures come
from a mobile viewport (touch, the page's viewport tag in force), as a phone shows them.
"""
import sys
from pathlib import Path

from PIL import Image
from playwright.sync_api import sync_playwright

OUT = Path(__file__).resolve().parents[1] / "docs" / "screenshots"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]
SIZES = {"projector": (1280, 720), "monitor": (1920, 1080), "tablet": (768, 1024),
         "phone": (390, 844)}
#: (name, link, what must be drawn before the picture is taken)
MODES = (("explore", "?scene=fig2", None), ("presenter", "?scene=fig4&presenter=1", None),
         ("compare", "?mode=compare", "compare_fig7d"),
         ("research", "?omega=2.62&mode=research", "regime_map"))
FILLED = """(name) => { const m = Bokeh.documents[0].get_model_by_name(name);
  if (!m) return false; const r = m.renderers ? m.renderers[0] : m;
  const d = r.data_source.data; const k = Object.keys(d)[0];
  return d[k].length > 0 && (name !== 'regime_map' ||
    Bokeh.documents[0].get_model_by_name('regime_map_figure').title.text.includes('complete')); }"""
READY = """() => window.Bokeh && Bokeh.documents.length &&
  Bokeh.documents[0].get_model_by_name('bifurcation_figure').title.text.includes('complete') &&
  Bokeh.documents[0].get_model_by_name('displacement').data_source.data.t.length > 0"""
#: The Fig. 4 animation a little before the mass comes to rest: the last impacts of a
#: chatter sequence (seek there, play at a quarter speed, shoot mid-way).
CHATTER = """() => {
  const d = Bokeh.documents[0];
  const st = d.get_model_by_name('displacement_sticking').data_source.data;
  const i = Math.max(0, st.start.length - 2);
  d.get_model_by_name('animation_time').value = st.start[i] - 0.6;
  return st.start[i];
}"""


def shoot(page, url, name, size, full_page=False, before=None):
    page.set_viewport_size({"width": size[0], "height": size[1]})
    page.goto(url)
    page.wait_for_function(READY, timeout=60_000, polling=200)
    page.wait_for_timeout(800)
    if before:
        before(page)
    page.wait_for_timeout(1200)              # titles fitted (app.views._figure)
    path = OUT / f"{name}.png"
    page.screenshot(path=str(path), full_page=full_page)
    Image.open(path).convert("RGB").quantize(256).save(path, optimize=True)
    print(path, path.stat().st_size // 1024, "KiB")


def chatter(page):
    page.locator(".ie-anim-speed select").select_option(label="0.25×")
    page.evaluate(CHATTER)
    page.locator(".ie-anim-play button").click()
    page.wait_for_timeout(1600)            # 0.4 s of motion at a quarter speed
    page.locator(".ie-anim-play button").click()


def main(url: str) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True,
                                    args=CHROMIUM_ARGS)
        page = browser.new_page()
        # the phone as a phone shows it: a mobile viewport (the page's viewport tag counts)
        phone = browser.new_context(viewport={"width": 390, "height": 844}, is_mobile=True,
                                    has_touch=True).new_page()
        for mode, query, drawn in MODES:
            for where, size in SIZES.items():
                wait = None if drawn is None else (
                    lambda p, n=drawn: p.wait_for_function(FILLED, arg=n, timeout=120_000))
                shoot(phone if where == "phone" else page, url + query, f"{mode}-{where}",
                      size, before=wait)
        shoot(page, url + "?scene=fig4", "animation-fig4-chatter", (1280, 720),
              before=chatter)
        browser.close()


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:5006/app")
