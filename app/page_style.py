"""The page's stylesheets (Panel ``stylesheets``, one per part of the layout) and the
script of its PNG export. The layout that uses them is ``app.controls``.

Each part's stylesheet lives in its own shadow root: a rule about a child (``.ie-bar``)
belongs to the stylesheet of the layout holding that child.
"""

#: Type of the readouts: at least 16 px (22 px in presenter mode, class ``ie-big``).
CSS = """
:host { font-size: 16px; }
:host(.ie-big) { font-size: 22px; }
.ie-badge b {color: #1f5fa8;}
.ie-accuracy {border-collapse: collapse; width: 100%;}
.ie-accuracy td, .ie-accuracy th {padding: 4px 10px; font-size: 15px; text-align: left;
                                  border-bottom: 1px solid #ddd; white-space: nowrap;}
"""
#: Below this width (CSS px) the page is one scrolling column: the header and the bar of
#: ω, r, c, g stay at the top (sticky) over views in two columns (one below 600 px).
NARROW = 899
WIDE = NARROW + 1
#: The page fills the window (no page scroll) from 900 px wide: a fixed header and bar,
#: one information line, and the active mode's plot area taking the rest.
#: ``ie-png-layout``: the size the PNG export lays the page out at (``PNG_JS``). No
#: minimum height: BokehJS gives the page the sum of its children's minimum heights as
#: laid out at load (the ten compare figures, opened from a link, ask for ~1100 px).
PAGE_CSS = f"""
:host {{ width: 100vw; height: 100vh !important; overflow: hidden; min-width: 0 !important;
         min-height: 0 !important; }}
@media (max-width: {NARROW}px) {{
  :host {{ height: auto !important; min-height: 100vh !important; overflow: visible; }}
}}
:host(.ie-png-layout) {{ width: var(--ie-png-width) !important;
                        height: var(--ie-png-height) !important; }}
"""
#: The bar (ω, r, c, g) comes first in the page, so that ω's box is the first Tab stop;
#: the header is drawn above it.
TOP_CSS = f"""
:host {{ flex: none !important; background: white; min-width: 0 !important; }}
.ie-header {{ order: -1; }}
@media (min-width: {WIDE}px) {{
  :host(.ie-big) {{ flex-direction: row !important; align-items: center;
                   border-bottom: 1px solid #ddd; background: #f6f8fb; }}
  :host(.ie-big) .ie-header {{ flex: 0 0 auto !important; width: auto !important;
                              border: none; }}
  :host(.ie-big) .ie-bar {{ flex: 1 1 0% !important; width: auto !important; }}
}}
@media (max-width: {NARROW}px) {{
  :host {{ position: sticky !important; top: 0; z-index: 50; box-shadow: 0 1px 4px #0003; }}
}}
"""
#: In presenter mode the header shares its line with the bar's four boxes: below 1400 px
#: the Reset button leaves it (it is there again out of presenter mode), so that the
#: boxes never overlap the mode switch.
HEADER_CSS = f"""
:host {{ flex-wrap: wrap; align-items: center; border-bottom: 1px solid #ddd;
         background: #f6f8fb; min-width: 0 !important; padding: 2px 0; }}
@media (min-width: {WIDE}px) {{
  :host(.ie-big) {{ flex-wrap: nowrap; border: none; background: none; }}
  :host(.ie-big) .ie-pin, :host(.ie-big) .ie-png {{ display: none !important; }}
  :host(.ie-big) .ie-scene {{ width: 150px !important; }}
  :host(.ie-big) .ie-notes {{ margin-right: 12px !important; }}
}}
@media (min-width: {WIDE}px) and (max-width: 1399px) {{
  :host(.ie-big) .ie-reset {{ display: none !important; }}
}}
"""
BAR_CSS = f"""
:host {{ display: grid !important; align-items: center; min-width: 0 !important;
        grid-template-columns: repeat(4, auto minmax(0, 1fr)); }}
.ie-bar-slider {{ width: auto !important; min-width: 0; }}
@media (max-width: {NARROW}px) {{
  :host {{ grid-template-columns: repeat(2, auto minmax(0, 1fr)); }}
}}
@media (min-width: {WIDE}px) {{
  :host(.ie-big) {{ grid-template-columns: repeat(4, auto); justify-content: end;
                   padding-left: 16px; }}
  :host(.ie-big) .ie-bar-slider {{ display: none !important; }}
  :host(.ie-big) .ie-bar-box {{ width: 104px !important; }}
}}
"""
#: A bar item's number box: its label (the symbol) beside it, not above.
BAR_ITEM_CSS = """
.bk-input-group { flex-direction: row !important; align-items: center; }
label { margin: 0 6px 0 0 !important; font-size: 18px; font-weight: bold; min-width: 0.9em; }
input { font-size: 16px; }
"""
#: The information line: caption (one line; the whole text on hover), chips for the
#: motion, the stability and the diagram, and a banner over it when there is a message.
#: Its height never changes, so results never move the figures.
INFO_CSS = f"""
:host {{ position: relative; flex: none !important; height: 30px; align-items: center;
         flex-wrap: nowrap; overflow: visible; z-index: 40; }}
@media (min-width: {WIDE}px) {{ :host(.ie-big) {{ height: 40px; }} }}
.ie-caption {{ flex: 1 1 0% !important; min-width: 80px; }}
.ie-badge, .ie-stability {{ flex: 0 1 auto !important; max-width: 25%; min-width: 0; }}
.ie-diagram-status {{ flex: 0 1 auto !important; max-width: 17%; min-width: 0; }}
.ie-message {{ position: absolute !important; left: 0; right: 0; top: 0; z-index: 45; }}
@media (max-width: {NARROW}px) {{
  :host {{ height: auto; flex-wrap: wrap; }}
  .ie-badge, .ie-stability, .ie-diagram-status {{ max-width: 100%; }}
}}
"""
#: A banner (bad link, work limit): one line over the information line; the whole
#: message while the pointer is on it.
MESSAGE_CSS = """
:host { font-size: 16px; background: #fff3cd; color: #664d03; border: 1px solid #ffe69c;
        border-radius: 4px; }
:host > div { padding: 3px 10px; max-height: 30px; overflow: hidden; white-space: nowrap;
              text-overflow: ellipsis; line-height: 24px; }
:host(:hover) > div { max-height: none; white-space: normal; }
"""
STAGE_CSS = f"""
:host {{ flex: 1 1 0% !important; min-height: 0; min-width: 0 !important; }}
@media (max-width: {NARROW}px) {{ :host {{ flex: none !important; height: auto !important; }} }}
"""
#: Explore: the four scene views in a row over the diagram (with its Lyapunov strip),
#: which gets three quarters of the width and the larger row; the animation beside it.
#: Narrower: two columns (one below 600 px) of fixed height, the diagram across.
EXPLORE_CSS = f"""
:host {{ display: grid !important; gap: 4px; height: 100% !important; min-height: 0;
        grid-template-columns: repeat(4, minmax(0, 1fr));
        grid-template-rows: minmax(0, 36fr) minmax(0, 64fr);
        grid-template-areas: "displacement phase impact_map poincare"
                             "bifurcation bifurcation bifurcation animation"; }}
:host(.ie-off) {{ display: none !important; }}
.ie-cell {{ min-width: 0; min-height: 0; height: auto !important; width: auto !important; }}
.ie-cell-displacement {{ grid-area: displacement; }}
.ie-cell-phase {{ grid-area: phase; }}
.ie-cell-impact_map {{ grid-area: impact_map; }}
.ie-cell-poincare {{ grid-area: poincare; }}
.ie-cell-bifurcation {{ grid-area: bifurcation; }}
.ie-cell-animation {{ grid-area: animation; }}
@media (max-width: {NARROW}px) {{
  :host {{ height: auto !important; grid-template-columns: repeat(2, minmax(0, 1fr));
          grid-template-rows: none; grid-auto-rows: 300px;
          grid-template-areas: "displacement phase" "impact_map poincare"
                               "bifurcation bifurcation" "bifurcation bifurcation"
                               "animation animation"; }}
}}
@media (max-width: 599px) {{
  :host {{ grid-template-columns: minmax(0, 1fr); grid-auto-rows: 280px;
          grid-template-areas: "displacement" "phase" "impact_map" "poincare"
                               "bifurcation" "bifurcation" "animation"; }}
}}
"""
#: Compare: Fig. 3 (a)-(e) over (f) and Fig. 7 (a)-(d); two columns of fixed height on a
#: tablet, one on a phone.
COMPARE_CSS = f"""
:host {{ display: grid !important; gap: 4px; height: 100% !important; min-height: 0;
        grid-template-columns: repeat(5, minmax(0, 1fr));
        grid-template-rows: repeat(2, minmax(0, 1fr)); }}
.ie-cell {{ min-width: 0; min-height: 0; height: auto !important; width: auto !important; }}
@media (max-width: {NARROW}px) {{
  :host {{ height: auto !important; grid-template-columns: repeat(2, minmax(0, 1fr));
          grid-template-rows: none; grid-auto-rows: 260px; }}
}}
@media (max-width: 599px) {{ :host {{ grid-template-columns: minmax(0, 1fr); }} }}
"""
#: Compare and research (a mode not shown has the class ``ie-off``): the plot area is theirs; what does not fit scrolls inside it.
ROOM_CSS = f"""
:host {{ height: 100% !important; min-height: 0; min-width: 0 !important; overflow: auto; }}
:host(.ie-off) {{ display: none !important; }}
@media (max-width: {NARROW}px) {{ :host {{ height: auto !important; overflow: visible; }} }}
:host(.ie-research) {{ overflow: hidden; }}
@media (max-width: {NARROW}px) {{
  :host(.ie-research) {{ flex: none !important; height: 90vh !important; }}
}}
"""
DRAWER_CSS = """
:host { position: fixed !important; top: 0; left: 0; bottom: 0; z-index: 900;
        background: white; overflow-y: auto; overflow-x: hidden;
        box-shadow: 4px 0 16px #0004; padding: 4px 0; max-width: 100vw; }
"""
#: A layout that fills its parent's height (research mode's tabs and their contents).
FILL_CSS = f"""
:host {{ min-height: 0; min-width: 0 !important; }}
@media (max-width: {NARROW}px) {{ :host {{ flex-wrap: wrap; }} }}
"""
#: A research figure and its legend: on a phone the legend goes under the figure, which
#: keeps the whole width (beside it, the map would be a strip a few dozen px wide).
FIGURE_ROW_CSS = """
@media (max-width: 599px) {
  :host { flex-direction: column !important; flex-wrap: nowrap !important; }
  :host > * { width: 100% !important; }
  :host > :first-child { flex: 1 1 0% !important; min-height: 300px; }
  :host > :not(:first-child) { flex: none !important; }
}
"""
#: A legend beside its figure: scrolls inside the plot area when it is taller.
LEGEND_CSS = f"""
:host {{ max-height: calc(100vh - 230px); overflow-y: auto; }}
@media (max-width: {NARROW}px) {{ :host {{ max-height: 30vh; width: 100% !important; }} }}
"""
#: The page's title and the notes' icon (the title left out on narrow screens and in
#: presenter mode, class ``ie-big`` on the header).
NOTE_CSS = """
.ie-title { font-size: 18px; margin-right: 8px; white-space: nowrap; vertical-align: middle; }
@media (max-width: 1099px) { .ie-title { display: none; } }
:host(.ie-big) .ie-title { display: none; }
details { font-size: 16px; color: #333; display: inline-block; vertical-align: middle; }
summary { cursor: pointer; list-style: none; font-size: 20px; }
details[open] div { position: fixed; z-index: 950; background: #fffbe8; margin: 2px 0;
                    padding: 6px 12px; border: 1px solid #e0c96b; border-radius: 4px;
                    right: 8px; width: min(46em, 90vw); font-size: 16px; color: #222; }
details div p { margin: 4px 0; }
.ie-notes-label { font-size: 16px; }
@media (max-width: 1499px) { .ie-notes-label { display: none; } }
"""
#: The readout lines (badge, stability, diagram status) keep one line's height whatever
#: their text: a result arriving never moves the figures under the pointer. The whole
#: text is the line's hover text.
LINE_CSS = """
:host { height: 24px; overflow: hidden; line-height: 24px; }
:host(.ie-big) { height: 32px; line-height: 32px; }
.ie-line, div { white-space: nowrap; overflow: hidden; text-overflow: ellipsis; }
"""
#: The caption: one line; the pointer on it (or a tap) shows all of it over the figures.
CAPTION_CSS = """
:host { height: 26px; position: relative; overflow: visible; font-size: 16px; }
:host(.ie-big) { height: 34px; font-size: 22px; }
:host > div { position: absolute; left: 0; right: 0; top: 0; background: white;
              white-space: nowrap; overflow: hidden; text-overflow: ellipsis;
              line-height: 26px; }
:host(:hover) > div { white-space: normal; z-index: 60; box-shadow: 0 4px 12px #0003;
                      padding: 0 6px; }
p { margin: 0 !important; display: inline; }
p + p { margin-left: 0.6em !important; }
"""
MODAL_CSS = """
:host { position: fixed !important; top: 6vh; left: 5vw; width: 90vw !important;
        max-height: 88vh; overflow: auto; z-index: 1000; background: white;
        border: 1px solid #999; border-radius: 6px; box-shadow: 0 8px 30px #0005;
        padding: 10px; }
"""
#: Size (CSS px) of the canvas the PNG export lays the page out for, whatever the window.
PNG_SIZE = (1600, 900)
#: Saves the active mode's figures as one PNG of ``PNG_SIZE`` (times the screen's pixel
#: ratio), laid out as on a window of that size whatever the window is: for a moment the
#: page is given that size and the stylesheets' width and height media rules answer as
#: for it (a phone's one column becomes the projector's grid); then each figure's canvas
#: is drawn where it sits in the plot area (BokehJS exports each plot; no server round
#: trip) and the page is given back its window. Laid out twice: once to learn the height
#: of the header at that width, once with the plot area PNG_SIZE's height. What it laid
#: out (canvas size, the header's height left out above, each figure's data area and its
#: box in the canvas) is left in ``window.__iePngLayout``.
PNG_JS = f"const [W, H] = [{PNG_SIZE[0]}, {PNG_SIZE[1]}];\n" + r"""
const figures = () => [...Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")]
  .map((v) => [v, v.el.getBoundingClientRect()]).filter(([v, b]) => b.width > 0 && b.height > 0);
const page = [...Bokeh.index.query((v) => (v.model.css_classes || []).includes("ie-page"))][0];
if (page == null || figures().length === 0) return;
const sheets = new Set();
const walk = (root) => {
  for (const s of [...(root.styleSheets || []), ...(root.adoptedStyleSheets || [])]) sheets.add(s);
  for (const e of root.querySelectorAll("*")) if (e.shadowRoot) walk(e.shadowRoot);
};
walk(document);
const answers = (text, h) => text.split(",").some((q) => {
  const parts = [...q.matchAll(/\((min|max)-(width|height):\s*([\d.]+)px\)/g)];
  return parts.length > 0 && parts.every(([, m, d, v]) => {
    const size = d === "width" ? W : h;
    return m === "min" ? size >= +v : size <= +v;
  });
});
const media = [];
const visit = (rules) => {
  for (const r of rules) {
    if (r.media && /(min|max)-(width|height)/.test(r.media.mediaText)) media.push([r, r.media.mediaText]);
    if (r.cssRules) visit(r.cssRules);
  }
};
for (const s of sheets) { try { visit(s.cssRules); } catch (e) { /* another origin's */ } }
const el = page.el;
const layOut = (h) => {
  for (const [r, text] of media) r.media.mediaText = answers(text, h) ? "all" : "not all";
  el.style.setProperty("--ie-png-width", `${W}px`);
  el.style.setProperty("--ie-png-height", `${h}px`);
  el.classList.add("ie-png-layout");
};
const restore = () => {
  for (const [r, text] of media) r.media.mediaText = text;
  el.classList.remove("ie-png-layout");
  el.style.removeProperty("--ie-png-width"); el.style.removeProperty("--ie-png-height");
};
const settle = (then) => setTimeout(() => requestAnimationFrame(() => requestAnimationFrame(then)), 700);
const draw = (top) => {
  const r = window.devicePixelRatio || 1;
  const canvas = document.createElement("canvas");
  canvas.width = Math.round(W * r); canvas.height = Math.round(H * r);
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "white"; ctx.fillRect(0, 0, canvas.width, canvas.height);
  const origin = el.getBoundingClientRect();
  const frames = {};
  for (const [v, b] of figures()) {
    const layer = v.export("png", true);
    ctx.drawImage(layer.canvas, (b.left - origin.left) * r, (b.top - origin.top - top) * r,
                  b.width * r, b.height * r);
    frames[v.model.name] = {frame: [v.frame.bbox.width, v.frame.bbox.height],
                            box: [b.left - origin.left, b.top - origin.top - top, b.width, b.height]};
  }
  window.__iePngLayout = {size: [W, H], top, frames};
  return canvas;
};
layOut(H);
settle(() => {
  const origin = el.getBoundingClientRect().top;
  const top = Math.max(0, Math.min(...figures().map(([v, b]) => b.top)) - origin - 8);
  layOut(H + top);
  settle(() => {
    let canvas;
    try { canvas = draw(top); } finally { restore(); }
    canvas.toBlob((blob) => {
      const a = document.createElement("a");
      a.href = URL.createObjectURL(blob);
      a.download = "impact_explorer.png";
      document.body.appendChild(a); a.click(); a.remove();
      setTimeout(() => URL.revokeObjectURL(a.href), 10000);
    }, "image/png");
  });
});
"""
