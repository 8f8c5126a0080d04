"""View 6: the motion animated — wall, spring, damper and mass drawn to scale in x,
with play / pause, step, speed and a time slider over the window shown on x(t).

Everything moves in the browser (``ANIMATE``, BokehJS): the frames are interpolated
from the displacement view's dense samples (cubic Hermite in x with the sampled ẋ, so
a flight between two impact corners is a smooth hop), impacts flash the wall, the
mass turns yellow while it sticks, and cursors move on the displacement plot and the
phase trajectory. The models it moves are ``syncable=False`` and the cursors take no
part in auto-ranging, so nothing travels to the server while it plays (and nothing
comes back).
"""
from __future__ import annotations

import numpy as np
from bokeh.layouts import column, row
from bokeh.models import (Button, ColumnDataSource, CustomJS, HoverTool, Label, MultiLine,
                          Quad, Range1d, Select, Slider)

from ..compute import SceneData
from ._figure import IMPACT, LINE, STICK, WALL, Kit, add_glyph, make_figure, style
from .base import View

#: Frames per second of the animation.
FPS = 30
#: Playback speeds (simulated seconds per second).
SPEEDS = ("0.1", "0.25", "0.5", "1", "2", "5", "10")
#: Mass width, and the damper's rod, as fractions of the motion's span (the rod is
#: longer than the span so that its cylinder never reaches the mass).
MASS_WIDTH, ROD = 0.14, 1.08

ANIMATE = """
const origin = cb_obj.origin || cb_obj;      // a button's click event, or a model
const action = origin === play ? "play" : origin === step ? "step"
             : origin === slider ? "seek" : origin === src ? "data" : "reset";
const st = mass.__ie || (mass.__ie = {playing: false, raf: null, last: null, tprev: null,
                                      flash: 0, stuck: null, flashing: null});
const I = info.data;
if (!I.g || I.g.length == 0) return;
const g = I.g[0], w = I.w[0], xs = I.xs[0], d = I.d[0], omega = I.omega[0], fs = I.fs[0];
const cyl = I.cyl[0], lw = I.lw[0], hs = I.hs[0], ww = I.ww[0];
const wall_px = 7 * lw;       // the wall: a line about ww wide, its face at x = g

function bsearch(a, t) {          // last index with a[i] <= t (-1: none)
  let lo = 0, hi = a.length - 1, ans = -1;
  while (lo <= hi) { const m = (lo + hi) >> 1; if (a[m] <= t) { ans = m; lo = m + 1; } else hi = m - 1; }
  return ans;
}
function state_at(t) {
  const T = src.data.t, X = src.data.x, V = src.data.v, n = T.length;
  if (n == 0) return [g, 0];
  const i = bsearch(T, t);
  if (i < 0) return [X[0], V[0]];
  if (i >= n - 1) return [X[n - 1], V[n - 1]];
  const h = T[i + 1] - T[i];
  if (h <= 0) return [X[i], V[i]];
  const s = (t - T[i]) / h, s2 = s * s, s3 = s2 * s;
  const x = (2 * s3 - 3 * s2 + 1) * X[i] + (s3 - 2 * s2 + s) * h * V[i]
          + (3 * s2 - 2 * s3) * X[i + 1] + (s3 - s2) * h * V[i + 1];
  return [x, V[i] + s * (V[i + 1] - V[i])];
}
function draw(t) {
  let [x, v] = state_at(t);
  x = Math.max(x, g);
  const a = x + w, L = xs - a;
  // impacts between the previous frame and this one flash the wall (while playing: a
  // paused frame is not redrawn when the flash ends)
  const ti = imp.data.t;
  if (st.playing && st.tprev != null && t > st.tprev && bsearch(ti, t) > bsearch(ti, st.tprev)) {
    st.flash = performance.now() + 140;
  }
  st.tprev = t;
  const flashing = performance.now() < st.flash;
  mass.data = {x: [x], v: [v], t: [t], left: [x], right: [a], bottom: [-0.32], top: [0.32]};
  const sx = [a, a + 0.1 * L], sy = [0.15, 0.15], N = 10;
  for (let k = 1; k < N; k++) { sx.push(a + 0.1 * L + 0.8 * L * k / N); sy.push(k %% 2 ? 0.24 : 0.06); }
  sx.push(a + 0.9 * L, xs); sy.push(0.15, 0.15);
  const F = Math.cos(omega * t), cx = x + 0.5 * w, tip = cx + F * fs, s = F >= 0 ? -1 : 1;
  const lines = [  // [xs, ys, colour, width]
    [[g - 0.5 * ww, g - 0.5 * ww], [-0.6, 0.6], flashing ? "%(impact)s" : "%(wall)s", 0], // wall
    [[xs, xs], [-0.6, 0.6], "%(wall)s", 2],                 // support
    [[cyl, xs], [-0.09, -0.09], "%(wall)s", 2],             // damper cylinder
    [[cyl, xs], [-0.25, -0.25], "%(wall)s", 2],
    [[g, xs], [-0.6, -0.6], "%(wall)s", 2],                 // floor
    [sx, sy, "#555555", 2],                                 // spring
    [[a, a + d], [-0.17, -0.17], "#555555", 3],             // damper rod and piston
    [[a + d, a + d], [-0.23, -0.11], "#555555", 3],
  ];
  if (Math.abs(F) > 0.05)                                   // the force cos(omega t)
    lines.push([[cx, tip], [0.5, 0.5], "%(impact)s", 3],
               [[tip + s * hs, tip, tip + s * hs], [0.58, 0.5, 0.42], "%(impact)s", 3]);
  lines_src.data = {xs: lines.map((l) => l[0]), ys: lines.map((l) => l[1]),
                    color: lines.map((l) => l[2]),
                    width: lines.map((l) => l[3] ? l[3] * lw : wall_px)};
  dcur.data = {t: [t], x: [x]};
  pcur.data = {x: [x], v: [v]};
  const k = bsearch(stick.data.start, t);
  const stuck = k >= 0 && t <= stick.data.end[k];
  if (stuck !== st.stuck) { mass_glyph.fill_color = stuck ? "%(stick)s" : "%(line)s"; st.stuck = stuck; }
  const what = stuck ? "sticking on the wall" : (flashing ? "impact!" : "free flight");
  label.text = "τ = " + t.toFixed(2) + " s   " + what;
}
const coarse = src.data.v.length == 0 || !(src.data.v[0] === src.data.v[0]);
function reset() {          // the time slider spans the samples of x(t) on screen
  if (st.raf != null) cancelAnimationFrame(st.raf);
  st.playing = false; st.raf = null; st.last = null; st.tprev = null;
  play.label = "▶ Play";
  const T = src.data.t, n = T.length;
  if (n < 2 || coarse) { label.text = "zoom in on x(τ) to animate"; return; }
  slider.start = T[0]; slider.end = T[n - 1];
  slider.step = Math.max((T[n - 1] - T[0]) / 20000, 1e-4);
  if (slider.value === T[0]) draw(slider.value); else slider.value = T[0];
}
function frame(now) {       // frames on a fixed 1/FPS schedule, time advanced by the clock
  if (!st.playing) return;
  if (st.last == null) { st.last = now; st.next = now; }
  if (now >= st.next - 2) {
    st.next = now - st.next > 100 ? now + 1000 / %(fps)d : st.next + 1000 / %(fps)d;
    const el = Math.min(now - st.last, 200);
    st.last = now;
    let t = slider.value + el / 1000 * parseFloat(speed.value);
    if (t > slider.end) { t = slider.start; st.tprev = null; }
    slider.value = t;
  }
  st.raf = requestAnimationFrame(frame);
}
function refit() {          // new samples of x(t) on screen: keep playing through them
  const T = src.data.t, n = T.length;
  if (n < 2 || coarse) { reset(); return; }
  slider.start = T[0]; slider.end = T[n - 1];
  const t = Math.min(Math.max(slider.value, T[0]), T[n - 1]);
  if (t === slider.value) draw(t); else slider.value = t;
}
if (action === "data" && st.ready != null) { refit(); return; }
if (st.ready == null || action === "reset" || action === "data") {
  st.ready = true;
  if (action !== "seek") reset();
}
if (coarse) return;
if (action === "seek") draw(slider.value);
else if (action === "play") {
  if (st.playing) {
    st.playing = false; if (st.raf != null) cancelAnimationFrame(st.raf); st.raf = null;
    play.label = "▶ Play";
  } else {
    st.playing = true; st.last = null; play.label = "Pause";
    st.raf = requestAnimationFrame(frame);
  }
} else if (action === "step") {
  st.playing = false; if (st.raf != null) cancelAnimationFrame(st.raf); st.raf = null;
  play.label = "▶ Play";
  slider.value = Math.min(slider.end, slider.value + parseFloat(speed.value) / %(fps)d);
}
""" % {"impact": IMPACT, "wall": WALL, "stick": STICK, "line": LINE, "fps": FPS}


#: Scene constants the browser draws with: wall at g, mass width, support, damper rod and
#: cylinder, ω, force arrow scale and head, line width factor (presenter mode).
INFO = ("g", "w", "xs", "d", "cyl", "omega", "fs", "hs", "lw", "ww")


def _local(**data) -> ColumnDataSource:
    """A source only the browser changes (never synced back to the server)."""
    return ColumnDataSource(data, syncable=False)


class AnimationView(View):
    key = "animation"
    note = ("The motion itself: the mass (blue) on its spring and damper, the wall at g "
            "on the left, drawn to scale in x. Press play: the arrow is the force "
            "cos ωτ, the wall flashes at each impact, the mass turns yellow while it "
            "rests on the wall.")

    def __init__(self, kit: Kit):
        self.info = ColumnDataSource({c: [] for c in INFO})
        self.mass = _local(x=[], v=[], t=[], left=[], right=[], bottom=[], top=[])
        self.lines = _local(xs=[], ys=[], color=[], width=[])
        self._presenter = False
        self.figure = fig = make_figure("animation_figure", "The motion", "displacement x",
                                        "", x_range=Range1d(-1.0, 1.0, syncable=False),
                                        y_axis_type=None,
                                        y_range=Range1d(-1.0, 0.75, syncable=False),
                                        tools="", kit=kit)
        fig.toolbar_location = None
        add_glyph(fig, MultiLine, self.lines, xs="xs", ys="ys", line_color="color",
                  line_width="width", name="animation_lines")
        body = add_glyph(fig, Quad, self.mass, left="left", right="right", bottom="bottom",
                         top="top", fill_color=LINE, line_color="#0b2f57", line_width=2,
                         name="animation_mass")
        body.glyph.syncable = False
        self.label = Label(x=8, y=8, x_units="screen", y_units="screen", text="",
                           text_font_size="14px", syncable=False)
        fig.add_layout(self.label)
        fig.add_tools(HoverTool(renderers=[body], tooltips=[
            ("τ", "@t{0.000} s"), ("x", "@x{0.0000}"), ("ẋ", "@v{0.0000}")]))
        fig.toolbar_location = None
        self.play = Button(label="▶ Play", width=84, css_classes=["ie-anim-play"],
                           syncable=False, button_type="primary")
        self.step = Button(label="Step ›", width=64, css_classes=["ie-anim-step"],
                           syncable=False)
        self.speed = Select(value="1", options=[(s, f"{s}×") for s in SPEEDS], width=64,
                            css_classes=["ie-anim-speed"], syncable=False)
        self.slider = Slider(start=0.0, end=1.0, value=0.0, step=0.01, title="",
                             sizing_mode="stretch_width", css_classes=["ie-anim-time"],
                             syncable=False, show_value=False, name="animation_time")
        self._root = column(fig, row(self.play, self.step, self.speed, self.slider,
                                     sizing_mode="stretch_width"),
                            sizing_mode="stretch_both", name="animation_layout")
        self._body_glyph = body.glyph

    @property
    def root(self):
        return self._root

    def link(self, views: dict) -> None:
        """Play from the displacement view's samples; move its cursor and the phase's."""
        disp, phase = views["displacement"], views["phase"]
        callback = CustomJS(code=ANIMATE, args=dict(
            src=disp.source, imp=disp.impacts, stick=disp.sticking, info=self.info,
            mass=self.mass, mass_glyph=self._body_glyph, lines_src=self.lines,
            label=self.label, dcur=disp.cursor, pcur=phase.cursor,
            slider=self.slider, play=self.play, step=self.step, speed=self.speed))
        self.play.js_on_event("button_click", callback)
        self.step.js_on_event("button_click", callback)
        self.slider.js_on_change("value", callback)
        self.info.js_on_change("data", callback)
        disp.source.js_on_change("data", callback)
        self.ready = callback

    def present(self, presenter: bool) -> None:
        style(self.figure, presenter)
        self.label.text_font_size = "22px" if presenter else "14px"
        self._presenter = presenter
        if self.info.data["g"]:
            self.info.data = {**self.info.data, "lw": [2.0 if presenter else 1.0]}

    def show_scene(self, scene: SceneData) -> None:
        """Scale the drawing to the motion; the browser resets the player."""
        run, tr = scene.run, scene.trajectory
        g = run.params.g
        x = np.asarray(tr["x"], dtype=float)
        lo = min(g, float(np.min(x))) if x.size else g
        hi = max(float(np.max(x)), g + 0.1) if x.size else g + 1.0
        span = max(hi - lo, 0.2)
        w, d = MASS_WIDTH * span, ROD * span
        cyl = hi + w + 0.03 * span               # open end of the damper's cylinder
        xs = hi + w + d + 0.12 * span            # support of the spring and the damper
        wall_w = 0.05 * span
        ww = 0.014 * (xs + 0.04 * span - lo + 1.5 * wall_w)   # ~7 px of a 500 px plot
        self.figure.x_range.update(start=lo - 1.5 * wall_w, end=xs + 0.04 * span)
        self.info.data = {"g": [g], "w": [w], "xs": [xs], "d": [d], "cyl": [cyl],
                          "omega": [run.params.omega], "fs": [0.6 * span],
                          "hs": [0.06 * span], "lw": [2.0 if self._presenter else 1.0],
                          "ww": [ww]}
        self.figure.title.text = f"The motion, ω = {run.params.omega:g}"

