"""The page's stylesheets (Panel ``stylesheets``, one per part of the layout) and the
script of its PNG export. The layout that uses them is ``app.controls``.
"""

CSS = """
.ie-badge {font-size: 14px;}
.ie-badge b {color: #1f5fa8;}
.ie-stability {font-size: 14px;}
.ie-accuracy {border-collapse: collapse; width: 100%;}
.ie-accuracy td, .ie-accuracy th {padding: 4px 10px; font-size: 15px; text-align: left;
                                  border-bottom: 1px solid #ddd; white-space: nowrap;}
"""
#: The page fills the window on a landscape screen of at least 1000 x 560 CSS px (a
#: projector at 1280 x 720 or 1920 x 1080): six cells, 3 x 2, no scrolling. Below that
#: (tablets, zoomed laptops) the views take two columns (one below 640 px) of fixed
#: height, the sidebar follows them, and the page scrolls down only.
PAGE_CSS = """
:host { width: 100%; }
@media (max-width: 999px), (max-height: 559px) {
  :host { flex-direction: column !important; height: auto !important; }
}
"""
SIDEBAR_CSS = """
:host { height: 100vh; overflow-y: auto; overflow-x: hidden; flex-shrink: 0; }
@media (max-width: 999px), (max-height: 559px) {
  :host { height: auto; width: 100% !important; overflow-y: visible; flex: none !important;
          order: 2; }
}
"""
MAIN_CSS = """
:host { height: 100vh; min-width: 0; flex: 1 1 0%; }
@media (max-width: 999px), (max-height: 559px) {
  :host { height: auto !important; flex: none !important; }
}
"""
GRID_CSS = """
:host { display: grid !important; grid-template-columns: repeat(3, minmax(0, 1fr));
        grid-template-rows: repeat(2, minmax(0, 1fr)); gap: 6px; flex: 1 1 0%;
        min-height: 0; width: 100%; }
@media (max-width: 999px), (max-height: 559px) {
  :host { grid-template-columns: repeat(2, minmax(0, 1fr)); grid-auto-rows: 340px;
          grid-template-rows: none; flex: none !important; height: auto !important; }
}
@media (max-width: 639px) { :host { grid-template-columns: minmax(0, 1fr); } }
"""
CELL_CSS = """
:host { min-width: 0; min-height: 0; height: 100%; position: relative; }
"""
NOTE_CSS = """
details { font-size: 13px; color: #555; }
summary { cursor: pointer; }
details[open] div { position: absolute; z-index: 20; background: #fffbe8; margin: 2px 0;
                    padding: 6px 12px; border: 1px solid #e0c96b; border-radius: 4px;
                    width: min(46em, 80vw); font-size: 15px; color: #222; }
details div p { margin: 4px 0; }
"""
#: The readout lines above the figures (badge, stability) keep one line's height whatever
#: their text: a result arriving never moves the figures under the pointer. The whole
#: text is the line's hover text.
LINE_CSS = """
:host { height: 20px; overflow: hidden; }
.ie-line { white-space: nowrap; overflow: hidden; text-overflow: ellipsis; }
"""
CAPTION_CSS = """
:host { max-height: 4.6em; overflow-y: auto; }
p { margin: 2px 0; }
"""
MODAL_CSS = """
:host { position: fixed !important; top: 6vh; left: 5vw; width: 90vw !important;
        max-height: 88vh; overflow: auto; z-index: 1000; background: white;
        border: 1px solid #999; border-radius: 6px; box-shadow: 0 8px 30px #0005;
        padding: 10px; }
"""
#: Saves every figure on the page as one PNG, drawn where it is on the page (BokehJS
#: exports each plot's canvas; no server round trip).
PNG_JS = """
const views = [...Bokeh.index.query((v) => v.model.constructor.__name__ === "Figure")];
const boxes = views.map((v) => [v, v.el.getBoundingClientRect()]).filter(([v, b]) => b.width > 0 && b.height > 0);
if (boxes.length === 0) return;
const x0 = Math.min(...boxes.map(([v, b]) => b.left)), y0 = Math.min(...boxes.map(([v, b]) => b.top));
const x1 = Math.max(...boxes.map(([v, b]) => b.right)), y1 = Math.max(...boxes.map(([v, b]) => b.bottom));
const r = window.devicePixelRatio || 1;
const canvas = document.createElement("canvas");
canvas.width = Math.round((x1 - x0 + 16) * r); canvas.height = Math.round((y1 - y0 + 16) * r);
const ctx = canvas.getContext("2d");
ctx.fillStyle = "white"; ctx.fillRect(0, 0, canvas.width, canvas.height);
for (const [v, b] of boxes) {
  const layer = v.export("png", true);
  ctx.drawImage(layer.canvas, (b.left - x0 + 8) * r, (b.top - y0 + 8) * r, b.width * r, b.height * r);
}
canvas.toBlob((blob) => {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = "impact_explorer.png";
  document.body.appendChild(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}, "image/png");
"""
