"""View 6: the largest Lyapunov exponent along the diagram's sweep, under the diagram and
sharing its x axis (the same ``x_range`` object), filled in with the diagram's chunks:
one point per swept value and chain (a sweep up and down gives two, in the diagram's
two colours).

λ₁ < 0 is a periodic attractor; λ₁ > 0 alone is not chaos: once the diagram is complete,
each value is classified as ``il.classify`` does (``app.motion_classes``) and only the
values it calls chaotic are drawn as chaos (red) and counted as such in the title, next to
those it calls unbounded and undetermined. A motion that sticks to the wall has λ₁ = −∞
and one whose exponent is undefined (unbounded growth, or a run stopped at a work limit)
NaN: both are drawn at the bottom edge, as a downward triangle and a cross, and counted
in the title, never dropped.
"""
from __future__ import annotations

import math

import numpy as np
from bokeh.models import ColumnDataSource, FixedTicker, Range1d, Scatter, Span

from ..state import Run
from ._figure import LINE, WALL, Kit, add_glyph, make_figure, padded, set_range
from .base import View
from .bifurcation import DOWN, UP

STICKS = ("inverted_triangle", "#7a5195")   # λ₁ = −∞: off the bottom
UNDEFINED = ("x", "#b35900")          # λ₁ NaN
FINITE = ("circle", LINE)
CHAOS = "#d1495b"                     # classify calls the motion chaotic
#: Finite exponents in the diagram's colours: independent starts, sweep up, sweep down.
SWEEP_COLORS = {0: LINE, 1: UP, -1: DOWN}

#: The y axis spans at least this much around 0, so that a strip of periodic motion
#: (λ₁ ≈ −0.1) does not blow noise up.
MIN_SPAN = 0.1


def _empty() -> dict:
    return {"omega": np.zeros(0), "lyapunov": np.zeros(0), "y": np.zeros(0),
            "sweep": np.zeros(0, dtype=np.int8), "marker": [], "color": [],
            "size": np.zeros(0), "chaos": np.zeros(0, dtype=bool)}


def strip_columns(values: np.ndarray, lam: np.ndarray, sweep: np.ndarray,
                  chaos: np.ndarray | None = None) -> tuple[dict, tuple]:
    """Columns of the strip (sorted by the swept value, then sweep up before down) and
    its y range: finite values as they are, -inf and NaN at the bottom edge with their
    own marker. ``sweep``: the chain of each value (0 independent, +1 up, -1 down);
    ``chaos``: values classify calls chaotic (drawn in CHAOS)."""
    order = np.lexsort((-sweep, values))
    x, lam, sweep = values[order], lam[order], sweep[order]
    chaos = np.zeros(x.size, bool) if chaos is None else np.asarray(chaos, bool)[order]
    finite = np.isfinite(lam)
    lo, hi = padded(lam[finite], include=(-MIN_SPAN / 2, MIN_SPAN / 2))
    bottom = lo + 0.03 * (hi - lo)
    y = np.where(finite, lam, bottom)
    sticks = lam == -np.inf
    marker = np.where(finite, FINITE[0], np.where(sticks, STICKS[0], UNDEFINED[0]))
    tint = np.array([SWEEP_COLORS[int(d)] for d in sweep], dtype=object)
    tint = np.where(chaos, CHAOS, tint)
    color = np.where(finite, tint, np.where(sticks, STICKS[1], UNDEFINED[1]))
    return ({"omega": x, "lyapunov": lam, "y": y, "sweep": sweep, "marker": marker.tolist(),
             "color": color.tolist(), "size": np.where(finite, np.where(chaos, 5.0, 3.0), 7.0),
             "chaos": chaos}, (lo, hi))


def strip_ticks(lo: float, hi: float) -> list[float]:
    """The strip's y ticks for the range (lo, hi) around 0: 0 and, on each side, a round
    value (1, 2 or 5 times a power of ten) within 90 % of that side, if it lies at least
    a quarter of the range away from 0. A strip ~60 px high has room for three labels,
    not the six a ticker places."""
    ticks = [0.0]
    for edge in (lo, hi):
        size = 0.9 * abs(edge)
        if size <= 0:
            continue
        unit = 10.0 ** math.floor(math.log10(size))
        step = max(m for m in (1, 2, 5) if m * unit <= size * (1 + 1e-12))
        tick = round(math.copysign(step * unit, edge), 12)
        if abs(tick) >= 0.25 * (hi - lo):
            ticks.append(tick)
    return sorted(ticks)


#: Height (px) of the strip under the diagram, on screen and in presenter mode.
STRIP_HEIGHT = {False: 110, True: 120}


class LyapunovView(View):
    key = "lyapunov"
    under = "bifurcation"

    def __init__(self, kit: Kit):
        self.source = ColumnDataSource(_empty())
        self.values: list[np.ndarray] = []
        self.exponents: list[np.ndarray] = []
        self.sweeps: list[np.ndarray] = []
        self.figure = make_figure("lyapunov_figure", "Largest Lyapunov exponent λ₁",
                                  None, "λ₁ (1/s)",
                                  y_range=Range1d(-MIN_SPAN, MIN_SPAN), tools="",
                                  toolbar_location=None, grid=False, kit=kit)
        # the x axis is labelled on the diagram right above
        # few Bokeh models per page: no tools (the x axis is the diagram's, zoomed there)
        # and no grid lines (the zero line is the one that matters)
        self.figure.yaxis.ticker = FixedTicker(ticks=strip_ticks(-MIN_SPAN, MIN_SPAN))
        self.figure.add_layout(Span(location=0.0, dimension="width", line_color=WALL,
                                    line_width=1, name="lyapunov_zero"))
        add_glyph(self.figure, Scatter, self.source, x="omega", y="y", size="size",
                  marker="marker", color="color", name="lyapunov")

    def present(self, presenter: bool) -> None:
        """The strip keeps a fixed height under the diagram; large type needs more."""
        super().present(presenter)
        self.figure.sizing_mode = "stretch_width"
        self.figure.height = STRIP_HEIGHT[presenter]

    def link(self, views: dict) -> None:
        """Share the diagram's x axis: zooming or panning one moves both."""
        self.figure.x_range = views["bifurcation"].figure.x_range

    def diagram_started(self, run: Run) -> None:
        self.values, self.exponents, self.sweeps = [], [], []
        self.source.data = _empty()
        self.figure.title.text = "Largest Lyapunov exponent λ₁ — computing"

    def diagram_chunk(self, part: dict) -> None:
        """All values so far in one assignment (the bottom edge moves with the data)."""
        self.values.append(part["values"])
        self.exponents.append(part["lyapunov"])
        self.sweeps.append(part["sweep"])
        self._draw(None)

    def diagram_classes(self, values, kinds) -> None:
        """classify's kind of each of ``values`` (None: the sweep is not classified)."""
        if values is None:
            self._draw(None, note="a sweep with warm starts is not classified")
        else:
            self._draw(dict(zip(np.asarray(values).tolist(), kinds)), classified=True)

    def _draw(self, kinds: dict | None, classified: bool = False,
              note: str = "not yet classified") -> None:
        values, lam = np.concatenate(self.values), np.concatenate(self.exponents)
        kind = np.array([kinds.get(v, "") for v in values.tolist()] if kinds else
                        [""] * values.size, dtype=object)
        data, (lo, hi) = strip_columns(values, lam, np.concatenate(self.sweeps),
                                       kind == "chaotic")
        self.source.data = data
        set_range(self.figure.y_range, lo, hi)
        self.figure.yaxis.ticker.ticks = strip_ticks(lo, hi)
        self.figure.title.text = strip_title(lam, kind, classified, note)


def strip_title(lam: np.ndarray, kind: np.ndarray, classified: bool,
                note: str = "not yet classified") -> str:
    """The strip's title: classify's counts once classified, else the signs of λ₁."""
    n = lam.size
    sticks = int(np.count_nonzero(lam == -np.inf))
    undefined = int(np.count_nonzero(np.isnan(lam)))
    # short enough for the strip's frame on a tablet
    edge = f"{sticks} stick (−∞ ▼) · {undefined} undefined (×)"
    if classified:
        counts = {k: int(np.count_nonzero(kind == k))
                  for k in ("chaotic", "unbounded", "undetermined")}
        return (f"λ₁: {counts['chaotic']} of {n} values chaotic (classify) · "
                f"{counts['unbounded']} unbounded · {counts['undetermined']} undetermined · "
                f"{edge}")
    positive = int(np.count_nonzero(lam > 0))
    return f"λ₁: {positive} of {n} values > 0 ({note}) · {edge}"
