"""Screenshots of the served app for the README (docs/screenshots/).

    panel serve app/app.py --port 5006 &
    .venv/bin/python scripts/screenshots.py http://127.0.0.1:5006/app

Takes the page at 1280 x 720 and 1920 x 1080 (projectors), 768 x 1024 (tablet, whole
page), presenter mode at 1280 x 720, and the Fig. 4 animation while the mass chatters
on the wall. Each PNG is reduced to a 256-colour palette to keep the repository small.
"""
import sys
from pathlib import Path

from PIL import Image
from playwright.sync_api import sync_playwright

OUT = Path(__file__).resolve().parents[1] / "docs" / "screenshots"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]
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
        shoot(page, url + "?scene=fig2", "projector-1280x720", (1280, 720))
        shoot(page, url + "?scene=fig6", "projector-1920x1080", (1920, 1080))
        shoot(page, url + "?scene=fig5", "tablet-768x1024", (768, 1024), full_page=True)
        shoot(page, url + "?scene=fig2&presenter=1", "presenter-1280x720", (1280, 720))
        shoot(page, url + "?scene=fig4", "animation-fig4-chatter", (1280, 720),
              before=chatter)
        browser.close()


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:5006/app")
