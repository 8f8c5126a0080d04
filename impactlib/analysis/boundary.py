"""Boundary curves: an event of a branch followed in two parameters.

An event of :func:`impactlib.continuation` (period-doubling, saddle-node, grazing) is a
point of codimension one: in the plane of the branch's parameter and a second one it lies
on a curve.  The unknowns are the branch's (impact times t_1..t_m, the velocities
u_1..u_m just before them, see :mod:`impactlib.continuation`) plus both parameters; the
2m equations of the multi-segment problem are joined by the event's defining condition,

    period-doubling   phi_PD = (-1)^m [P (1 + det M) + tr M~] = 0    (|P| det(M + I))
    saddle-node       phi_SN = (-1)^m [P (1 + det M) - tr M~] = 0    (|P| det(M - I))
    grazing, impact   u_j = 0                      (the j-th impact has zero speed)
    grazing, flight   x(t_j + s) = g, v(t_j + s) = 0     (flight j touches the wall at s,
                                                          s one more unknown)

(standard defining systems of codimension-one bifurcations, Kuznetsov, Elements of
Applied Bifurcation Theory, 3rd ed., ch. 10), so 2m + 1 (+1) equations in 2m + 2 (+1)
unknowns define a curve, followed by Keller's pseudo-arclength method as the branches
are: predictor along the tangent, Newton on the equations plus the arclength condition,
so the curve passes its folds in either parameter.  Derivatives: the multi-segment
Jacobian is exact; the condition rows and the parameter columns are central differences.

Watched along the curve (sign changes located by Illinois false position on the
arclength, each a labelled point):

* period-doubling and saddle-node curves: the orbit must stay admissible (every impact
  speed above 0, every flight above the wall; the test of
  :func:`impactlib.continuation`).  Where it stops being so, the event meets a grazing,
  a codimension-two point, and the curve ends there.
* grazing curves: the multipliers of the grazing orbit (the touch itself not counted:
  the orbit on the side where it does not impact) through -1 or +1, labelled as the
  grazing meeting a period-doubling or saddle-node; the curve goes on.  Another impact
  or flight reaching the wall, or the touch reaching an impact, or the touch losing its
  curvature, ends it (a codimension-two point).
* turning points of the curve in either parameter ("fold in r"), and points where it
  turns in both at once ("cusp", where two saddle-node curves meet).

The curve ends at ``stop`` in the second parameter, at a closed edge of either
parameter's valid range (both landed on exactly), at a codimension-two point, where the
corrector fails with the smallest step, where it closes on itself, or after
``max_points``; ``message`` says which.
"""
from __future__ import annotations

import io
import math
from dataclasses import dataclass, field

import numpy as np

from ..io.header import write_csv
from ..kernels.flight import start_segment, system_constants
from ..kernels.grazing import lowest_in_flight
from ..model import FIELDS, PARAM_NAMES, Params
from .boundary_system import CLEARANCE_SAMPLES, CurveSystem
from .continuation import Event, ds_problems, locate_on_step, stop_problems

KINDS = ("period-doubling", "saddle-node", "grazing")
COS_TURN = 0.995        # smallest cosine between successive tangents (about 5.7 degrees)
MU_STEP = 0.2           # largest change of a multiplier per step on grazing curves
MU_WATCH = 3.0


@dataclass(frozen=True)
class BoundaryPoint:
    """A labelled point of a boundary curve: its start, a fold, a codimension-two point,
    its end.  ``values`` = (first parameter, second parameter); ``index`` its row in the
    curve's arrays."""

    label: str
    values: tuple
    index: int


@dataclass(frozen=True)
class Boundary:
    """Result of :func:`boundary`: one row per point along the curve (labelled points
    included, in order).

    kind : "period-doubling", "saddle-node" or "grazing".
    names : (first, second) parameter names; values : (k, 2) their values.
    x, v : (k,) the orbit's state on the section t = phase.
    multipliers : (k, 2) complex, largest modulus first (on a grazing curve those of the
        orbit on the side where the touch is no impact).
    impact_times, impact_velocities : (k, m) the orbit's unknowns.
    touch_times : (k,) where a grazing orbit touches the wall (nan on other curves).
    points : tuple of :class:`BoundaryPoint`.  message : why the curve ended.
    n, impacts, phase : the orbit type and its section; params : the event's parameters
        (all but the two named stay fixed); condition : the defining condition in words.
    """

    kind: str
    names: tuple
    values: np.ndarray
    x: np.ndarray
    v: np.ndarray
    multipliers: np.ndarray
    impact_velocities: np.ndarray
    points: tuple
    message: str
    n: int = 1
    impacts: int = 0
    phase: float = 0.0
    params: Params | None = field(default=None, repr=False)
    condition: str = ""
    impact_times: np.ndarray | None = field(default=None, repr=False)
    touch_times: np.ndarray | None = field(default=None, repr=False)

    @property
    def orbit(self) -> str:
        """The orbit type, as the branches and the regime map name it."""
        return f"{self.impacts}-impact period-{self.n}"

    def __repr__(self):
        a, b = self.names
        lines = [f"Boundary({self.kind} of the {self.orbit} orbit in ({a}, {b}), "
                 f"{len(self.values)} points, {self.condition})"]
        lines += [f"  {q.label} at ({a}, {b}) = ({q.values[0]:.10g}, {q.values[1]:.10g})"
                  for q in self.points]
        lines.append(f"  {self.message}")
        return "\n".join(lines)

    def columns(self) -> dict:
        """The curve as equally long named columns (parameters, state, multipliers,
        impact unknowns)."""
        cols = {self.names[0]: self.values[:, 0], self.names[1]: self.values[:, 1],
                "x": self.x, "v": self.v}
        for i in range(2):
            cols[f"mu{i + 1}_re"] = self.multipliers[:, i].real
            cols[f"mu{i + 1}_im"] = self.multipliers[:, i].imag
        for j in range(self.impact_velocities.shape[1]):
            cols[f"t{j + 1}"] = self.impact_times[:, j]
            cols[f"u{j + 1}"] = self.impact_velocities[:, j]
        cols["touch_t"] = self.touch_times
        return cols

    def header(self) -> dict:
        """What the curve was computed with, for the ``# name = value`` lines of a CSV."""
        h = {"kind": self.kind, "orbit": self.orbit, "condition": self.condition,
             "param_x": self.names[0], "param_y": self.names[1]}
        for n in PARAM_NAMES:
            if n not in self.names:
                h[n] = repr(getattr(self.params, n))
        h.update({"n": str(self.n), "impacts": str(self.impacts), "phase": repr(self.phase),
                  "points": "; ".join(f"{q.label} at row {q.index}" for q in self.points),
                  "message": self.message})
        return h

    def to_csv(self, path=None) -> str:
        """The curve as CSV text (also written to ``path`` if given): ``# name = value``
        lines (both parameter names, the event kind, the orbit type, the fixed
        parameters), a header row, one row per point, numbers read back bit for bit.
        ``pandas.read_csv(io.StringIO(text), comment="#")`` reads it."""
        buf = io.StringIO()
        write_csv(buf, self.columns(), self.header())
        if path is not None:
            with open(path, "w", encoding="utf-8", newline="") as f:
                f.write(buf.getvalue())
        return buf.getvalue()

    def to_frame(self):
        """The curve as a pandas DataFrame (header in ``attrs``)."""
        import pandas as pd
        df = pd.DataFrame(self.columns())
        df.attrs.update(self.header())
        return df


def _check(event, name, stop, ds, max_points):
    problems = []
    ok_event = isinstance(event, Event) and event.impact_times is not None
    if not isinstance(event, Event):
        problems.append(f"event={event!r} is not an Event of impactlib.continuation(...).events")
    elif event.impact_times is None:
        problems.append(f"event={tuple(event)!r} carries no orbit (build it with "
                        "impactlib.continuation)")
    elif event.kind not in KINDS:
        problems.append(f"event kind {event.kind!r} has no boundary curve here; expected one "
                        f"of {', '.join(KINDS)}")
        ok_event = False
    if name not in PARAM_NAMES:
        problems.append(f"name={name!r} is not a parameter; expected one of "
                        f"{', '.join(PARAM_NAMES)}")
    elif ok_event and name == event.name:
        problems.append(f"name={name!r} is the event's own parameter; the second parameter "
                        "must be another one")
    stop_f = None
    if isinstance(stop, bool):
        problems.append(f"stop={stop!r} is not a number")
    else:
        try:
            stop_f = float(stop)
        except (TypeError, ValueError):
            problems.append(f"stop={stop!r} is not a number")
    if stop_f is None:
        pass
    elif not math.isfinite(stop_f):
        problems.append(f"stop={stop!r} is not finite")
    elif ok_event and name in PARAM_NAMES and name != event.name:
        problems += stop_problems(event.params, name, stop_f)
    problems += ds_problems(ds)
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)) \
            or max_points < 2:
        problems.append(f"max_points={max_points!r} must be a whole number >= 2")
    if problems:
        raise ValueError("invalid boundary: " + "; ".join(problems))
    return stop_f


def _touch_of(event):
    """Which grazing a grazing event is: ("impact", j) or ("flight", j, s)."""
    p = event.params
    sp = system_constants(p.m, p.c, p.k, p.g, p.r, p.omega)
    ts = np.asarray(event.impact_times, dtype=float)
    us = np.asarray(event.impact_velocities, dtype=float)
    total = event.n * p.T
    m = ts.size
    j_imp = int(np.argmax(us))
    best = (-float(us[j_imp]), ("impact", j_imp), None)
    for j in range(m):
        t1 = ts[j + 1] if j + 1 < m else ts[0] + total
        seg = start_segment(sp, ts[j], p.g, -p.r * us[j])
        low, s = lowest_in_flight(sp, seg, t1 - ts[j], math.nan, CLEARANCE_SAMPLES)
        if abs(low) < abs(best[0]):
            best = (low, ("flight", j), s)
    return best[1], best[2]


def _edges(name):
    """Closed edges of a parameter's valid range (landed on exactly)."""
    f = FIELDS[name]
    out = []
    if f.lo is not None and not f.lo_open:
        out.append(f.lo)
    if f.hi is not None:
        out.append(f.hi)
    return out


def _condition_text(kind, touch):
    if touch is None:
        return "a multiplier at -1" if kind == "period-doubling" else "a multiplier at +1"
    if touch[0] == "impact":
        return f"impact {touch[1] + 1} at zero speed"
    return f"flight {touch[1] + 1} touches the wall"


def boundary(event, name: str, stop: float, *, ds: float | None = None,
             max_points: int = 2000) -> Boundary:
    """Follow a branch's event in the plane of its parameter and ``name``.

    Pseudo-arclength continuation of the orbit's multi-segment unknowns plus the event's
    defining condition (see the module notes), from the event towards ``stop`` in the
    second parameter, through folds of the curve, with codimension-two points (the event
    meeting a grazing; a grazing meeting a period-doubling or saddle-node) and folds
    labelled in ``points``.

    Parameters
    ----------
    event : Event
        A period-doubling, saddle-node or grazing event from
        ``impactlib.continuation(...).events``: its kind, parameter, orbit type, section
        and parameters come with it.
    name : one of "m", "c", "k", "g", "r", "omega", not the event's own parameter.
    stop : float
        Target value of the second parameter.
    ds : float, optional
        Largest move of the two parameters in one step (default |stop - start| / 200);
        steps are smaller where the curve turns or the corrector labours.
    max_points : int

    Returns
    -------
    Boundary
        ``values[:, 0]`` the event's parameter, ``values[:, 1]`` the second one.
    """
    stop = _check(event, name, stop, ds, max_points)
    kind, names = event.kind, (event.name, name)
    p = event.params
    n, phase = int(event.n), float(event.phase)
    ts0 = np.asarray(event.impact_times, dtype=float)
    us0 = np.asarray(event.impact_velocities, dtype=float)
    m = ts0.size
    touch, s_touch = (None, None) if kind != "grazing" else _touch_of(event)
    curve = CurveSystem(p, names, n, m, phase, kind, touch)
    extra = [s_touch] if curve.q else []
    lam0 = (event.value, getattr(p, name))
    y = np.concatenate([ts0, us0, extra, lam0])
    span = abs(stop - lam0[1])
    # a step moves the parameters by at most ``plane`` (so that the curve is drawn smoothly
    # in the plane) and the unknowns by at most ds_max; smaller where the curve turns
    # (COS_TURN) or the corrector labours
    plane = span / 200.0 if ds is None else float(ds)
    ds = plane
    ds_min = 1e-9 * max(1.0, span)
    ds_max = 50.0 * plane
    nz = curve.nz
    unit = np.eye(nz)

    def result(rows, points, message):
        ys = np.array([r[0] for r in rows]) if rows else np.empty((0, nz))
        return Boundary(
            kind=kind, names=names, values=ys[:, -2:].copy(),
            x=np.array([r[1] for r in rows]), v=np.array([r[2] for r in rows]),
            multipliers=np.array([r[3] for r in rows]).reshape(-1, 2),
            impact_velocities=ys[:, m:2 * m].copy(), points=tuple(points), message=message,
            n=n, impacts=m, phase=phase, params=p, condition=_condition_text(kind, touch),
            impact_times=ys[:, :m].copy(), touch_times=np.array([r[4] for r in rows]))

    # the event is located to ~1e-9 on its branch: polish it at the start value of name
    y1, _ = curve.correct(y, unit[-1], lam0[1])
    if y1 is None:
        return result([], [], "the corrector failed at the event: its defining condition "
                              "is singular there")
    y = y1
    rows, points = [], []

    def add(yp, label=None):
        x, v, mu, touch_t, tests = curve.describe(yp)
        rows.append((yp.copy(), x, v, mu, touch_t))
        if label is not None:
            points.append(BoundaryPoint(label, (float(yp[-2]), float(yp[-1])), len(rows) - 1))
        return tests

    tests_prev = add(y, "start")
    t = curve.tangent(y)
    if t[-1] * (stop - lam0[1]) < 0.0 or (t[-1] == 0.0 and t[-2] < 0.0):
        t = -t
    t_start, y_start = t.copy(), y.copy()
    edges = [_edges(names[0]), [stop] + _edges(names[1])]
    watched = ["wall"] if touch is None else [
        "wall", "curvature", "period-doubling", "saddle-node"] + (
        ["touch inside"] if curve.q else [])
    message = f"reached max_points={max_points}"

    def at(yp):
        return f"({names[0]}, {names[1]}) = ({yp[-2]:.10g}, {yp[-1]:.10g})"

    while len(rows) < max_points:
        h = min(ds, plane / max(float(np.linalg.norm(t[-2:])), 1e-12))
        y_pred = y + h * t
        land = None
        for k in (0, 1):
            i = nz - 2 + k
            for b in edges[k]:
                if (y[i] - b) * (y_pred[i] - b) <= 0.0 and y[i] != b and t[i] != 0.0:
                    frac = (b - y[i]) / (h * t[i])
                    if land is None or frac < land[0]:
                        land = (frac, i, b)
        y_new = None
        if land is not None:
            frac, i, b = land
            y_new, its = curve.correct(y + frac * h * t, unit[i], b)
            if y_new is None:
                # a curve that meets the edge tangentially is not landed on: step along it
                land = None
        if y_new is None:
            y_new, its = curve.correct(curve.clip(y_pred), t, t @ y + h)
        t_new = None
        if y_new is not None:
            try:
                # the corrector's last Jacobian: its tangent differs by ~1e-12 from one
                # evaluated at y_new, one Jacobian less per point
                t_new = curve.tangent(y_new, t, curve.last_jacobian)
            except ValueError:
                y_new = None
            else:
                if float(t_new @ t) < COS_TURN and h > ds_min:
                    y_new = None
        if y_new is None:
            if h <= ds_min:
                try:
                    curve.params(y[-2:] + ds_min * t[-2:])
                    message = f"the corrector failed at the smallest step at {at(y)}"
                except ValueError:
                    message = f"reached the edge of the valid range at {at(y)}"
                break
            ds = max(0.5 * h, ds_min)
            continue
        x, v, mu, touch_t, tests = curve.describe(y_new)
        if touch is not None and h > ds_min:
            mu_prev = rows[-1][3]
            if (np.max(np.abs(mu - mu_prev)) > MU_STEP
                    and min(np.max(np.abs(mu)), np.max(np.abs(mu_prev))) < MU_WATCH):
                ds = max(0.5 * h, ds_min)
                continue
        s_step = float(t @ (y_new - y))
        found = []
        for key in watched:
            a, b = tests_prev.get(key, math.nan), tests.get(key, math.nan)
            if math.isfinite(a) and math.isfinite(b) and (a > 0) != (b > 0) and a != 0.0:
                ye = _locate(curve, y, t, s_step, lambda q, key=key: curve.describe(q)[4][key],
                             a, b)
                if ye is None and key not in ("period-doubling", "saddle-node"):
                    ye = y_new      # not located (the corrector fails near it): the step's end
                if ye is not None:
                    found.append((float(t @ (ye - y)), key, ye))
        for k, pname in enumerate(names):
            i = nz - 2 + k
            if t[i] * t_new[i] < 0.0:
                ye = _locate(curve, y, t, s_step,
                             lambda q, i=i: curve.tangent(q, t)[i], t[i], t_new[i])
                if ye is not None:
                    found.append((float(t @ (ye - y)), f"fold in {pname}", ye))
        found.sort(key=lambda e: e[0])
        found = _cusps(found)
        ended = False
        for _, key, ye in found:
            if key.startswith("fold") or key == "cusp":
                add(ye, key)
            elif key in ("period-doubling", "saddle-node"):
                add(ye, f"grazing meets {key}")
            else:
                what = {"wall": f"{kind} meets grazing" if touch is None else "double grazing",
                        "curvature": "degenerate grazing (no curvature at the touch)",
                        "touch inside": "the touch reaches an impact"}[key]
                add(ye, what)
                message = f"ended at a codimension-two point: {what} at {at(ye)}"
                ended = True
                break
        if ended:
            break
        tests_prev = add(y_new)
        if land is not None:
            i, b = land[1], land[2]
            pname = names[i - (nz - 2)]
            if i == nz - 1 and b == stop:
                message = f"reached {pname} = {stop:g}"
                points.append(BoundaryPoint("end", (float(y_new[-2]), float(y_new[-1])),
                                            len(rows) - 1))
            else:
                message = f"reached the edge of the valid range of {pname} ({pname} = {b:g})"
                points.append(BoundaryPoint(f"edge of {pname}", (float(y_new[-2]),
                                                                 float(y_new[-1])),
                                            len(rows) - 1))
            break
        if len(rows) > 3 and _passes(y_start, y, y_new) and float(t_new @ t_start) > 0.9:
            message = f"the curve closed on itself at {at(y_start)}"
            break
        y, t = y_new, t_new
        if its <= 3:
            ds = min(h * 1.4, ds_max)
        elif its >= 6:
            ds = max(h * 0.6, ds_min)
    return result(rows, points, message)


def _cusps(found):
    """Folds in both parameters at one point are a cusp of the curve in the plane (where
    two saddle-node curves meet): one labelled point."""
    out = []
    for item in found:
        if (out and item[1].startswith("fold") and out[-1][1].startswith("fold")
                and item[1] != out[-1][1] and np.max(np.abs(item[2] - out[-1][2]))
                <= 1e-6 * (1.0 + np.max(np.abs(item[2])))):
            out[-1] = (out[-1][0], "cusp", out[-1][2])
        else:
            out.append(item)
    return out


def _passes(y0, ya, yb):
    """The step from ya to yb passes within a quarter of its length of y0."""
    d = yb - ya
    L2 = float(d @ d)
    if L2 == 0.0:
        return False
    w = min(1.0, max(0.0, float((y0 - ya) @ d) / L2))
    return float(np.linalg.norm(ya + w * d - y0)) < 0.25 * math.sqrt(L2)


def _locate(curve, y0, t0, s_hi, test, f_lo, f_hi):
    """The point of the step (y0, t0, arclength s_hi) where ``test`` is zero."""
    return locate_on_step(lambda s: curve.correct(y0 + s * t0, t0, t0 @ y0 + s)[0], test,
                          s_hi, f_lo, f_hi)
