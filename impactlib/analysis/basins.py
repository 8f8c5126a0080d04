"""Basins of attraction on a Poincare section t = phase (mod T).

Each start (x0, v0) at t0 = phase is followed one forcing period at a time by the exact
kernel; only its section points are kept.  A start has settled on a period-n orbit when
the n-period map's displacements |P_j - P_{j-n}| over the last n points are below the
settling tolerance and so is each point's distance to its limit, estimated from the last
three displacements as if the map were linear (:func:`_tail_error`: both multipliers
count, so a slow mode that hardly moves the points is not mistaken for convergence).
A settled start then stops: the work per start is its transient, not a fixed window.
Distinct periodic attractors are told apart by comparing their section points as SETS,
within the sum of the two orbits' error bounds (times a safety factor); never by a
tolerance on one point.
Starts that have not settled after ``max_periods`` periods are grouped by the bounding box
of their last ``n_window`` section points; one member of each group is classified by
:func:`impactlib.classify` on a fresh record window, and a group becomes a chaotic
attractor only when classify calls that run chaotic.  Once a chaotic attractor is known,
later starts stop at the end of the first window of ``n_window`` section points whose
box matches it (a window still holding the transient is larger), instead of running to
``max_periods``.  Everything else is undecided (-1), with the reason in
``message``.

The grid runs in row blocks on the sweeps' shared thread pool (``nogil`` kernels);
:func:`iter_basins` streams the blocks, :func:`basins` collects them.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..kernels._jit import jit
from .classify import MAX_PERIOD, classify, describe
from ..kernels.flight import FA, OM
from ..model import Params, RunLimits
from ..kernels import engine as E
from ..kernels.engine import Buffers
from ..model import RunStatus
from ..parallel import run_tasks
from ..progress import reporter, stopped
from ..simulate import run_constants, simulate
from ..io.result import SweepResult

SETTLE_RTOL = 1e-6         # settling tolerance, relative to the grid's scale (see _scale)
ROUND_RTOL = 1e-10         # error floor: rounding accumulated over an orbit's flights and
                           # impacts (orbits with sticking reached 6e-12 relative at n = 15)
SET_FACTOR = 4.0           # safety factor on the summed error bounds when comparing orbits
BOX_RTOL = 0.1             # chaotic boxes agree within this fraction of their extent
MAX_CELLS = 1_000_000
MAX_CLASSIFY = 16          # classify runs per call, for starts that never settled
MAX_ATTRACTORS = 64        # more distinct orbits than this: a continuum, not attractors
UNBOUNDED_FACTOR = 1e12    # |x| or |v| beyond this many grid scales: unbounded

# per-start outcomes of the kernel
SETTLED, UNSETTLED, WORK_LIMIT, UNBOUNDED = 0, 1, 2, 3
ON_CHAOTIC = 16             # + row of the known chaotic box the start's points fill


@jit
def _cycle_displacement(hx, hv, k, n, size, stop_above):
    """max |P_j - P_{j-n}| over j = k-n+1..k (ring buffer of ``size``); returns early once
    above ``stop_above``."""
    e = 0.0
    for j in range(k - n + 1, k + 1):
        a = j % size
        b = (j - n) % size
        d = max(abs(hx[a] - hx[b]), abs(hv[a] - hv[b]))
        if d > e:
            e = d
            if e > stop_above:
                return e
    return e


@jit
def _tail_error(hx, hv, j, n, size):
    """Distance from P_j to the limit of P_j, P_{j+n}, ... if the n-period map were linear.

    With the differences D_i = P_{j-i n} - P_{j-(i+1) n}, the map's Jacobian solves
    M [D_2 D_1] = [D_1 D_0], and the rest of the sequence sums to
    P* - P_j = M (I - M)^{-1} D_0 (vector extrapolation, as in minimal polynomial
    extrapolation: Sidi, Vector Extrapolation Methods (2017), ch. 1).  Both multipliers
    count, the slow one included, even when it barely shows in D_0.  Returns inf when M
    is not a contraction (or not determined).
    """
    a0 = j % size
    a1 = (j - n) % size
    a2 = (j - 2 * n) % size
    a3 = (j - 3 * n) % size
    d0x = hx[a0] - hx[a1]
    d0v = hv[a0] - hv[a1]
    d1x = hx[a1] - hx[a2]
    d1v = hv[a1] - hv[a2]
    d2x = hx[a2] - hx[a3]
    d2v = hv[a2] - hv[a3]
    det = d2x * d1v - d1x * d2v
    n1 = math.hypot(d1x, d1v)
    n2 = math.hypot(d2x, d2v)
    if n1 == 0.0:
        return 0.0 if d0x == 0.0 and d0v == 0.0 else np.inf
    if abs(det) <= 1e-8 * n1 * n2:
        # one direction only: a scalar multiplier
        mu = (d0x * d1x + d0v * d1v) / (n1 * n1)
        if not abs(mu) < 1.0:
            return np.inf
        f = abs(mu / (1.0 - mu))
        return f * max(abs(d0x), abs(d0v))
    # M = [D1 D0] [D2 D1]^{-1}
    i11 = d1v / det
    i12 = -d1x / det
    i21 = -d2v / det
    i22 = d2x / det
    m11 = d1x * i11 + d0x * i21
    m12 = d1x * i12 + d0x * i22
    m21 = d1v * i11 + d0v * i21
    m22 = d1v * i12 + d0v * i22
    tr = m11 + m22
    dm = m11 * m22 - m12 * m21
    disc = tr * tr - 4.0 * dm
    if disc >= 0.0:
        rad = 0.5 * (abs(tr) + math.sqrt(disc))
    else:
        rad = math.sqrt(abs(dm))
    if not rad < 1.0:
        return np.inf
    # e = M (I - M)^{-1} D0
    b11 = 1.0 - m11
    b12 = -m12
    b21 = -m21
    b22 = 1.0 - m22
    bd = b11 * b22 - b12 * b21
    y1 = (b22 * d0x - b12 * d0v) / bd
    y2 = (-b21 * d0x + b11 * d0v) / bd
    ex = m11 * y1 + m12 * y2
    ev = m21 * y1 + m22 * y2
    return max(abs(ex), abs(ev))


@jit
def _matching_box(box, boxes, rtol):
    """Row of ``boxes`` that ``box`` agrees with (see _box_match), or -1."""
    for q in range(boxes.shape[0]):
        ext = max(box[1] - box[0], box[3] - box[2], boxes[q, 1] - boxes[q, 0],
                  boxes[q, 3] - boxes[q, 2], 1e-300)
        ok = True
        for i in range(4):
            if abs(box[i] - boxes[q, i]) > rtol * ext:
                ok = False
        if ok:
            return q
    return -1


@jit
def _settled_period(hx, hv, k, size, max_period, settle_tol, round_tol):
    """(n, error bound) of the smallest period n <= max_period the section points up to
    the k-th (ring buffers hx, hv of ``size``) have settled on, or (0, 0.0)."""
    for n in range(1, max_period + 1):
        if 3 * n > k:
            break
        e_now = _cycle_displacement(hx, hv, k, n, size, settle_tol)
        if e_now > settle_tol:
            continue
        if e_now <= round_tol:
            return n, round_tol
        if k < 4 * n - 1:
            continue
        err = 0.0
        for j in range(k - n + 1, k + 1):
            err = max(err, _tail_error(hx, hv, j, n, size))
        if err <= settle_tol:
            return n, max(err, round_tol)
    return 0, 0.0


@jit
def _smallest_repeat(hx, hv, k, n, size, gap_tol):
    """The smallest divisor d of n at which the last n points repeat within ``gap_tol``:
    a slow approach (a multiplier near -1) can pass the settling test at a multiple of
    the true period first."""
    for d in range(1, n):
        if n % d != 0:
            continue
        ok = True
        for j in range(k - n + 1 + d, k + 1):
            p1 = j % size
            p0 = (j - d) % size
            gap = max(abs(hx[p1] - hx[p0]), abs(hv[p1] - hv[p0]))
            if gap > gap_tol:
                ok = False
                break
        if ok:
            return d
    return n


@jit
def _record_orbit(hx, hv, hm, hc, k, n, size, pts):
    """The last n section points into pts (n, 2), in time order; returns the impacts and
    the chatter sequences summed in those n periods."""
    m = 0
    c = 0
    for j in range(k - n + 1, k + 1):
        a = j % size
        pts[j - (k - n + 1), 0] = hx[a]
        pts[j - (k - n + 1), 1] = hv[a]
        m += hm[a]
        c += hc[a]
    return m, c


@jit
def follow_starts(sp, rate, hmax, phase, x0s, v0s, settle_tol, round_tol, set_factor, huge,
                  max_periods, max_period, n_window, chaos_boxes, box_rtol, max_impacts,
                  max_steps, outcome, n_out, m_out, chat_out, pts_out, err_out, box_out,
                  fin_out, used_out):
    """Follow each start (x0s[s], v0s[s]) at t = phase period by period until it settles.

    Outputs per start s: outcome (SETTLED, UNSETTLED, WORK_LIMIT, UNBOUNDED), n_out the
    period n, m_out the impacts in the last n periods, chat_out the chatter sequences summed
    in them (> 0: complete chattering), pts_out[s, :n] the last n section points in time
    order, err_out their error bound, box_out (x_min, x_max, v_min, v_max) of the last
    complete window of ``n_window`` points, fin_out (t, x, v) where it stopped, used_out
    the periods run.

    ``chaos_boxes`` (q, 4) are the boxes of chaotic attractors already found: a start
    not settled whose last window's box matches one of them (within ``box_rtol`` of the
    extent, as :func:`_box_match`) stops at the end of that window, outcome
    ON_CHAOTIC + its row in chaos_boxes, instead of running to max_periods.
    """
    period = 2.0 * math.pi / sp[OM]
    size = 4 * max_period + 1
    hx = np.empty(size)
    hv = np.empty(size)
    hm = np.zeros(size, dtype=np.int64)
    hc = np.zeros(size, dtype=np.int64)
    empty = np.empty(0)
    buf = Buffers(empty, empty, np.empty((0, 2)), empty, empty, empty, empty, empty, empty,
                  empty, np.empty((0, 2)))
    ctl = E.controls(phase, phase, hmax, rate, 0.0, 1e-6, 1e-9, max_impacts, max_steps,
                     E.EXACT, E.NO_TANGENT)
    run = np.empty(E.NRES)
    for s in range(x0s.shape[0]):
        t = phase
        x = x0s[s]
        v = v0s[s]
        hx[0] = x
        hv[0] = v
        hm[0] = 0
        hc[0] = 0
        n_imp = 0
        n_steps = 0
        res = UNSETTLED
        box = np.array([np.inf, -np.inf, np.inf, -np.inf])
        wbox = box.copy()
        k = 0
        while k < max_periods:
            k += 1
            t_next = phase + k * period
            ctl[E.T_END] = t_next
            ctl[E.T_RECORD] = t
            ctl[E.MAX_IMPACTS] = max(1, max_impacts - n_imp)
            ctl[E.MAX_STEPS] = max(1, max_steps - n_steps)
            st = E.run_engine(sp, ctl, t, x, v, buf, run)
            x, v = run[E.X_F], run[E.V_F]
            n_rec, n_tail = int(run[E.N_REC]), int(run[E.N_TAIL])
            t = t_next
            n_imp += int(run[E.N_TOT])
            n_steps += int(run[E.NSTEPS])
            if (st == RunStatus.IMPACT_LIMIT or st == RunStatus.STEP_LIMIT
                    or n_imp >= max_impacts or n_steps >= max_steps):
                res = WORK_LIMIT
                break
            if not (abs(x) <= huge and abs(v) <= huge):
                res = UNBOUNDED
                break
            a = k % size
            hx[a] = x
            hv[a] = v
            hm[a] = n_rec
            hc[a] = n_tail
            wbox[0] = min(wbox[0], x)
            wbox[1] = max(wbox[1], x)
            wbox[2] = min(wbox[2], v)
            wbox[3] = max(wbox[3], v)
            if k % n_window == 0:
                box[:] = wbox
                wbox[0] = np.inf
                wbox[1] = -np.inf
                wbox[2] = np.inf
                wbox[3] = -np.inf
                hit = _matching_box(box, chaos_boxes, box_rtol)
                if hit >= 0:
                    res = ON_CHAOTIC + hit
                    break
            found, err = _settled_period(hx, hv, k, size, max_period, settle_tol, round_tol)
            if found > 0:
                n = _smallest_repeat(hx, hv, k, found, size, set_factor * err + round_tol)
                m_out[s], chat_out[s] = _record_orbit(hx, hv, hm, hc, k, n, size, pts_out[s])
                n_out[s] = n
                err_out[s] = err
                res = SETTLED
                break
        outcome[s] = res
        box_out[s, 0] = box[0]
        box_out[s, 1] = box[1]
        box_out[s, 2] = box[2]
        box_out[s, 3] = box[3]
        fin_out[s, 0] = t
        fin_out[s, 1] = x
        fin_out[s, 2] = v
        used_out[s] = k


# ---------------------------------------------------------------- Python layer


@dataclass(frozen=True)
class Attractor:
    """One attractor found on the section.

    ``points`` are its section points, (k, 2) columns (x, v): the n points of a periodic
    orbit in time order, or for a chaotic attractor the record window of the run classify
    judged.  ``error`` bounds the distance of a periodic orbit's points from the true
    orbit; ``box`` is (x_min, x_max, v_min, v_max); ``lyapunov`` and ``lyapunov_error``
    are the largest exponent classify measured on a chaotic attractor (NaN otherwise).
    """

    label: str            # e.g. "3-impact period-3", "chaotic (∞-impact period-∞)"
    kind: str             # "periodic", "complete chattering", "no impact" or "chaotic"
    impacts: float        # m per orbit (math.inf for chattering and chaos)
    period: float         # n forcing periods (math.inf for chaos)
    points: np.ndarray
    error: float
    box: tuple
    lyapunov: float = math.nan
    lyapunov_error: float = math.nan

    def same_orbit(self, points: np.ndarray, error: float) -> bool:
        """Whether a periodic orbit's points are this one's, compared as sets."""
        if self.kind == "chaotic" or points.shape[0] != self.points.shape[0]:
            return False
        return bool(_sets_match(self.points, points[None], SET_FACTOR * (self.error + error))[0])


@dataclass(frozen=True)
class BasinRows:
    """A block of finished rows from :func:`iter_basins`.

    ``labels`` (rows, nx) index ``attractors`` (everything found so far, in order of
    discovery: an index never changes meaning, later blocks only append); -1 undecided.
    """

    start: int            # first row index (into v)
    labels: np.ndarray
    periods: np.ndarray   # (rows, nx) forcing periods followed per start (the work spent)
    attractors: tuple
    rows_done: int
    rows_total: int
    message: str


@dataclass(frozen=True, repr=False, eq=False)
class Basins(SweepResult):
    """Result of :func:`basins`.

    ``labels[i, j]`` is the attractor (index into ``attractors``) that the start
    (x[j], v[i]) at t0 = phase settles on; -1 undecided.  ``fractions[a]`` is the share of
    all nx * nv cells in the basin of attractor a; ``undecided`` the share of -1.
    ``x`` (nx,) and ``v`` (nv,) are the grid of starts (length, length per time unit),
    ``phase`` the section (s), ``periods`` (nv, nx) the forcing periods followed per start,
    ``complete`` False when a time limit stopped it, ``elapsed`` seconds (not part of
    ``==``), ``attractors`` the :class:`Attractor` found, in order of discovery,
    ``params`` the parameters and ``message`` what stopped it or "complete".
    """

    params: Params
    phase: float
    x: np.ndarray
    v: np.ndarray
    labels: np.ndarray
    attractors: tuple
    fractions: np.ndarray
    undecided: float
    periods: np.ndarray       # (nv, nx) forcing periods run per start (the work spent)
    complete: bool            # False when a time limit stopped it (rows not run stay -1)
    message: str
    elapsed: float


def _sets_match(ref, cand, tol):
    """For candidates cand (s, n, 2): whether each is the point set ref (n, 2) within tol
    (every point of either has a partner in the other within tol, max norm)."""
    d = np.abs(cand[:, :, None, :] - ref[None, None, :, :]).max(axis=-1)   # (s, n, n)
    near = d <= np.asarray(tol).reshape(-1, 1, 1)
    return near.any(axis=2).all(axis=1) & near.any(axis=1).all(axis=1)


def _box_match(a, b):
    """Two (x_min, x_max, v_min, v_max) boxes agree within BOX_RTOL of their extent."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    ext = max(a[1] - a[0], a[3] - a[2], b[1] - b[0], b[3] - b[2], 1e-300)
    return bool(np.all(np.abs(a - b) <= BOX_RTOL * ext))


def _pair(name, value, kind, problems):
    try:
        lo, hi = value
    except (TypeError, ValueError):
        problems.append(f"{name}={value!r} must be a pair ({'lo, hi' if kind else 'nx, nv'})")
        return None
    out = []
    for part in (lo, hi):
        if isinstance(part, bool) or part is None:
            problems.append(f"{name}={value!r} holds {part!r}, not a number")
            return None
        if kind:
            try:
                f = float(part)
            except (TypeError, ValueError):
                problems.append(f"{name}={value!r} holds {part!r}, not a number")
                return None
            if not math.isfinite(f):
                problems.append(f"{name}={value!r} holds a non-finite bound")
                return None
            out.append(f)
        else:
            if not isinstance(part, (int, np.integer)):
                problems.append(f"{name}={value!r} must hold whole numbers")
                return None
            out.append(int(part))
    return tuple(out)


def _check(p, x_range, v_range, n, phase, max_periods, n_window, time_limit):
    if not isinstance(p, Params):
        raise TypeError(f"p must be impactlib.Params, got {type(p).__name__}")
    problems: list[str] = []
    xr = _pair("x_range", x_range, True, problems)
    vr = _pair("v_range", v_range, True, problems)
    if isinstance(n, (int, np.integer)) and not isinstance(n, bool):
        n = (int(n), int(n))
    nn = _pair("n", n, False, problems)
    if xr is not None:
        if xr[0] > xr[1]:
            problems.append(f"x_range={x_range!r} must be increasing (lo <= hi)")
        if xr[0] < p.g:
            problems.append(f"x_range={x_range!r} starts below the wall g={p.g!r} "
                            "(starts need x >= g)")
    if vr is not None and vr[0] > vr[1]:
        problems.append(f"v_range={v_range!r} must be increasing (lo <= hi)")
    if nn is not None:
        if min(nn) < 1:
            problems.append(f"n={n!r} must be at least 1 cell per side")
        elif nn[0] * nn[1] > MAX_CELLS:
            problems.append(f"n={n!r} asks for {nn[0] * nn[1]} cells; at most {MAX_CELLS}")
        else:
            if xr is not None and nn[0] > 1 and xr[0] == xr[1]:
                problems.append(f"x_range={x_range!r} is empty for nx={nn[0]} cells")
            if vr is not None and nn[1] > 1 and vr[0] == vr[1]:
                problems.append(f"v_range={v_range!r} is empty for nv={nn[1]} cells")
    try:
        ph = float(phase)
    except (TypeError, ValueError):
        ph = math.nan
    if isinstance(phase, bool) or not (0.0 <= ph <= p.T):
        problems.append(f"phase={phase!r} must lie in [0, T={p.T!r}] (time units)")
    if isinstance(max_periods, bool) or not isinstance(max_periods, (int, np.integer)) \
            or not (3 * MAX_PERIOD <= max_periods <= 1_000_000):
        problems.append(f"max_periods={max_periods!r} must be a whole number in "
                        f"[{3 * MAX_PERIOD}, 1000000]")
    elif isinstance(n_window, bool) or not isinstance(n_window, (int, np.integer)) \
            or not (8 <= n_window <= max_periods):
        problems.append(f"n_window={n_window!r} must be a whole number in [8, max_periods]")
    if time_limit is not None:
        try:
            tl = float(time_limit)
        except (TypeError, ValueError):
            tl = math.nan
        if isinstance(time_limit, bool) or not tl > 0:
            problems.append(f"time_limit={time_limit!r} must be a number > 0 (seconds) or None")
    if problems:
        raise ValueError("invalid basins: " + "; ".join(problems))
    return xr, vr, nn, ph


def _scale(p, xr, vr):
    """Size of the section's region of interest: the grid's corners, the wall, and the
    amplitude of the forced response (an orbit's size), whichever is largest."""
    sp, _, _ = run_constants(p)
    return max(abs(xr[0]), abs(xr[1]), abs(vr[0]), abs(vr[1]), abs(p.g), float(sp[FA]),
               1e-300)




# ------------------------------------------------------------------ drivers


class _Registry:
    """Attractors found so far; labels are indices into ``items`` (append only)."""

    def __init__(self, p, phase, n_window):
        self.p = p
        self.phase = phase
        self.n_window = n_window
        self.items: list[Attractor] = []
        self.groups: list[tuple] = []     # (box, attractor index or -1, verdict label)
        self.classified = 0
        self.unsettled_left = 0            # unsettled starts left undecided
        self.limited = 0                   # starts stopped by a work ceiling
        self.unbounded = 0
        self.overflow = 0                  # settled starts beyond MAX_ATTRACTORS orbits
        self.verdicts: dict[str, int] = {}
        # boxes of the chaotic attractors found, read by blocks as they start (replaced,
        # never mutated: a block sees one consistent snapshot)
        self.chaos_boxes = np.empty((0, 4))
        self.chaos_index: list[int] = []

    def _add(self, att):
        self.items.append(att)
        return len(self.items) - 1

    def periodic(self, m, n, chat, pts, err):
        """Indices for settled starts (arrays over the block)."""
        lab = np.full(m.shape[0], -1, dtype=np.int64)
        for s in range(m.shape[0]):
            if lab[s] >= 0:
                continue
            k = int(n[s])
            cand = [i for i, a in enumerate(self.items)
                    if a.kind != "chaotic" and a.points.shape[0] == k]
            hit = next((i for i in cand if self.items[i].same_orbit(pts[s, :k], err[s])), -1)
            if hit < 0 and len(self.items) >= MAX_ATTRACTORS:
                self.overflow += 1
                continue
            if hit < 0:
                mm = -1 if chat[s] > 0 else int(m[s])
                mo = describe(mm, k)
                P = pts[s, :k].copy()
                hit = self._add(Attractor(
                    label=mo.label, kind=mo.kind, impacts=mo.impacts, period=mo.period,
                    points=P, error=float(err[s]),
                    box=(P[:, 0].min(), P[:, 0].max(), P[:, 1].min(), P[:, 1].max())))
            # the rest of the block at once: same period, sets within tolerance
            same = (n == k) & (lab < 0)
            idx = np.nonzero(same)[0]
            a = self.items[hit]
            ok = _sets_match(a.points, pts[idx, :k], SET_FACTOR * (a.error + err[idx]))
            lab[idx[ok]] = hit
            lab[s] = hit
        return lab

    def unsettled(self, box, fin, count=True):
        lab = np.full(box.shape[0], -1, dtype=np.int64)
        for s in range(box.shape[0]):
            g = next((g for g in self.groups if _box_match(g[0], box[s])), None)
            if not count:
                # a probe: keep only a chaotic verdict (its short run may not have settled)
                if g is None and self.classified < MAX_CLASSIFY:
                    self._classify(box[s], fin[s], keep_other=False)
                continue
            if g is None:
                if self.classified >= MAX_CLASSIFY:
                    self.unsettled_left += 1
                    self.verdicts["not classified (classify budget spent)"] = \
                        self.verdicts.get("not classified (classify budget spent)", 0) + 1
                    continue
                g = self._classify(box[s], fin[s])
            if g[1] < 0:
                self.unsettled_left += 1
                self.verdicts[g[2]] = self.verdicts.get(g[2], 0) + 1
            lab[s] = g[1]
        return lab

    def _classify(self, box, fin, keep_other=True):
        p = self.p
        t0, x0, v0 = float(fin[0]), max(float(fin[1]), p.g), float(fin[2])
        w = self.n_window * p.T
        sol = simulate(p, t_end=t0 + 2 * w, t_record=t0 + w, x0=x0, v0=v0, t0=t0,
                       phase=self.phase)
        self.classified += 1
        mo = classify(sol)
        idx = -1
        if mo.kind == "chaotic":
            P = np.column_stack([sol.poincare.x, sol.poincare.v])
            cbox = (P[:, 0].min(), P[:, 0].max(), P[:, 1].min(), P[:, 1].max())
            idx = self._add(Attractor(label=mo.label, kind="chaotic", impacts=mo.impacts,
                                      period=mo.period, points=P, error=math.nan, box=cbox,
                                      lyapunov=getattr(mo, "lyapunov", math.nan),
                                      lyapunov_error=getattr(mo, "lyapunov_error", math.nan)))
            self.chaos_index.append(idx)
            self.chaos_boxes = np.vstack([self.chaos_boxes, np.asarray(box, dtype=float)])
        g = (tuple(box), idx, mo.label)
        if idx >= 0 or keep_other:
            self.groups.append(g)
        return g

    def message(self, rows_done, rows_total, stopped):
        parts = []
        if stopped:
            parts.append(f"stopped by time_limit after {rows_done} of {rows_total} rows "
                         "(rows not run are -1)")
        if self.unsettled_left:
            why = ", ".join(f"{c} {v}" for v, c in self.verdicts.items())
            parts.append(f"{self.unsettled_left} starts had not settled on a periodic orbit "
                         f"and are not on a chaotic attractor: {why}")
        if self.limited:
            parts.append(f"{self.limited} starts stopped at a work ceiling (max_impacts, "
                         "max_steps)")
        if self.unbounded:
            parts.append(f"{self.unbounded} starts grew without bound")
        if self.overflow:
            parts.append(f"{self.overflow} starts settled on orbits beyond the first "
                         f"{MAX_ATTRACTORS} distinct ones (left -1): a continuum of neutral "
                         "orbits rather than attractors")
        if self.p.c == 0.0 and self.p.r == 1.0:
            parts.append("no dissipation (c = 0, r = 1): the section map preserves area, so "
                         "nothing attracts; orbits found are neutral, not attractors")
        return "; ".join(parts) if parts else "complete"


def _block(reg, sp, rate, hmax, phase, xs, v_rows, settle_tol, round_tol, huge, max_periods,
           n_window, max_impacts, max_steps, pairs=False):
    # the grid rows v_rows x xs, or with pairs the starts (xs[i], v_rows[i])
    nx = xs.size
    x0s = xs if pairs else np.tile(xs, v_rows.size)
    v0s = v_rows if pairs else np.repeat(v_rows, nx)
    k = x0s.size
    outcome = np.zeros(k, dtype=np.int64)
    n_out = np.zeros(k, dtype=np.int64)
    m_out = np.zeros(k, dtype=np.int64)
    chat = np.zeros(k, dtype=np.int64)
    pts = np.full((k, MAX_PERIOD, 2), np.nan)
    err = np.zeros(k)
    box = np.zeros((k, 4))
    fin = np.zeros((k, 3))
    used = np.zeros(k, dtype=np.int64)
    follow_starts(sp, rate, hmax, phase, x0s, v0s, settle_tol, round_tol, SET_FACTOR, huge,
                  max_periods, MAX_PERIOD, n_window, reg.chaos_boxes, BOX_RTOL, max_impacts,
                  max_steps, outcome, n_out, m_out, chat, pts, err, box, fin, used)
    return outcome, n_out, m_out, chat, pts, err, box, fin, used


def iter_basins(p: Params, x_range, v_range, n=(100, 100), phase: float = 0.0, *,
                max_periods: int = 1000, n_window: int = 128, rows_per_block: int | None = None,
                workers: int | None = None, time_limit: float | None = None,
                limits: RunLimits = RunLimits()):
    """Stream the basins grid of :func:`basins` as blocks of finished rows.

    Yields :class:`BasinRows` in row order (rows of v, bottom first).  Stop iterating (or
    ``close()`` the generator) to cancel: blocks not yet started are dropped.  Arguments
    as in :func:`basins`; validation happens before the first block is computed.
    """
    xr, vr, (nx, nv), phase = _check(p, x_range, v_range, n, phase, max_periods, n_window,
                                     time_limit)
    return _iter(p, xr, vr, nx, nv, phase, max_periods, n_window, rows_per_block, workers,
                 time_limit, limits)


def _iter(p, xr, vr, nx, nv, phase, max_periods, n_window, rows_per_block, workers,
          time_limit, limits, tasks=None):
    """The blocks of rows, each ``_block(reg, ...)``: through ``tasks(fn, args_list)``, a
    generator of the results in order (default: the shared thread pool's ``run_tasks``;
    :mod:`impactlib.sweeps.distributed` passes a Dask cluster's)."""
    tic = time.perf_counter()
    xs = np.linspace(*xr, nx)
    vs = np.linspace(*vr, nv)
    sp, rate, hmax = run_constants(p)
    scale = _scale(p, xr, vr)
    settle_tol, round_tol = SETTLE_RTOL * scale, ROUND_RTOL * scale
    huge = UNBOUNDED_FACTOR * scale
    per = rows_per_block or max(1, math.ceil(256 / nx))
    # one row first, for a quick first picture; then blocks of ``per`` rows
    starts = [0] + list(range(1, nv, per)) if rows_per_block is None and nv > 1 else \
        list(range(0, nv, per))
    stops = starts[1:] + [nv]
    reg = _Registry(p, phase, n_window)
    common = (settle_tol, round_tol, huge, max_periods, n_window, limits.max_impacts,
              limits.max_steps)
    # probes spread over the grid, run first for two windows: a chaotic attractor they
    # find is known to every block from the start (its starts then stop after a window)
    ix = np.unique([nx // 2, nx // 4, (3 * nx) // 4])
    iv = np.unique([nv // 2, nv // 4, (3 * nv) // 4])
    px, pv = np.meshgrid(xs[ix], vs[iv])
    probe = (settle_tol, round_tol, huge, min(max_periods, 2 * n_window), n_window,
             limits.max_impacts, limits.max_steps)
    outcome, *_, box, fin, _ = _block(reg, sp, rate, hmax, phase, px.ravel(), pv.ravel(),
                                      *probe, pairs=True)
    un = outcome == UNSETTLED
    if un.any():
        reg.unsettled(box[un], fin[un], count=False)
    args = [(reg, sp, rate, hmax, phase, xs, vs[a:b], *common) for a, b in zip(starts, stops)]
    done = 0
    stopped = False
    gen = (run_tasks(_block, args, workers) if tasks is None else tasks(_block, args))
    try:
        for a, res in zip(starts, gen):
            outcome, n_out, m_out, chat, pts, err, box, fin, used = res
            lab = np.full(outcome.size, -1, dtype=np.int64)
            ok = outcome == SETTLED
            if ok.any():
                lab[ok] = reg.periodic(m_out[ok], n_out[ok], chat[ok], pts[ok], err[ok])
            un = outcome == UNSETTLED
            if un.any():
                lab[un] = reg.unsettled(box[un], fin[un])
            known = outcome >= ON_CHAOTIC
            if known.any():
                lab[known] = np.asarray(reg.chaos_index)[outcome[known] - ON_CHAOTIC]
            reg.limited += int(np.sum(outcome == WORK_LIMIT))
            reg.unbounded += int(np.sum(outcome == UNBOUNDED))
            rows = lab.reshape(-1, nx)
            done += rows.shape[0]
            if time_limit is not None and time.perf_counter() - tic > time_limit and done < nv:
                stopped = True
            yield BasinRows(start=a, labels=rows, periods=used.reshape(-1, nx),
                            attractors=tuple(reg.items), rows_done=done, rows_total=nv,
                            message=reg.message(done, nv, stopped))
            if stopped:
                break
    finally:
        gen.close()


def basins(p: Params, x_range, v_range, n=(100, 100), phase: float = 0.0, *,
           max_periods: int = 1000, n_window: int = 128, workers: int | None = None,
           time_limit: float | None = None, limits: RunLimits = RunLimits(), progress=None,
           cancel=None) -> Basins:
    """Which attractor each start of a grid on the section t = phase settles on.

    Parameters
    ----------
    p : Params
    x_range, v_range : (lo, hi)
        The grid is ``x = linspace(*x_range, nx)``, ``v = linspace(*v_range, nv)``; every
        start needs x >= g (starts behind the wall are refused).
    n : (nx, nv)
        Cells per side (an int means nx = nv = n); at most 10^6 cells.
    phase : float
        The section, in time units in [0, T]: every start is at t0 = phase.
    max_periods : int
        Ceiling on the forcing periods followed per start; a start not settled by then is
        classified (chaotic) or left undecided.
    n_window : int
        Section points in the bounding box of an unsettled start and in classify's record
        window.
    workers : int
        Threads of the shared sweep pool; 1 runs in the calling thread.
    time_limit : float, optional
        Seconds; when passed, no further rows start and the result is partial
        (``complete`` False, rows not run -1, said in ``message``).
    limits : RunLimits
        Impact and step ceilings per start.
    progress : True or callable, optional
        A tqdm bar (True) or ``progress(rows_done, nv)`` after each block of rows.
    cancel : threading.Event, optional
        Once set, no further block starts (rows not run stay -1, ``complete`` False).

    Returns
    -------
    Basins
    """
    if progress is not None or cancel is not None:
        return _basins_in_blocks(p, x_range, v_range, n, phase, max_periods=max_periods,
                                 n_window=n_window, workers=workers, time_limit=time_limit,
                                 limits=limits, progress=progress, cancel=cancel)
    xr, vr, (nx, nv), phase = _check(p, x_range, v_range, n, phase, max_periods, n_window,
                                     time_limit)
    tic = time.perf_counter()
    return collect(p, xr, vr, nx, nv, phase, tic,
                   _iter(p, xr, vr, nx, nv, phase, max_periods, n_window, None, workers,
                         time_limit, limits))


def collect(p, xr, vr, nx, nv, phase, tic, blocks) -> Basins:
    """The :class:`Basins` of a grid from all its ``BasinRows`` blocks."""
    labels = np.full((nv, nx), -1, dtype=np.int64)
    periods = np.zeros((nv, nx), dtype=np.int64)
    last = None
    for blk in blocks:
        rows = slice(blk.start, blk.start + blk.labels.shape[0])
        labels[rows] = blk.labels
        periods[rows] = blk.periods
        last = blk
    atts = last.attractors if last else ()
    counts = np.bincount(labels[labels >= 0], minlength=len(atts))[:len(atts)]
    total = labels.size
    return Basins(params=p, phase=phase, x=np.linspace(*xr, nx), v=np.linspace(*vr, nv),
                  labels=labels, attractors=atts, fractions=counts / total,
                  undecided=float(np.sum(labels < 0)) / total, periods=periods,
                  complete=bool(last is not None and last.rows_done == nv),
                  message=last.message if last else "complete",
                  elapsed=time.perf_counter() - tic)


def _basins_in_blocks(p, x_range, v_range, n=(100, 100), phase: float = 0.0, *,
                      progress=None, cancel=None, rows_per_block=None, **kwargs) -> Basins:
    """:func:`impactlib.basins` from the blocks of :func:`impactlib.iter_basins`, with
    ``progress`` (rows done) and ``cancel`` (rows not run stay -1, ``complete`` False)."""
    tic = time.perf_counter()
    gen = iter_basins(p, x_range, v_range, n=n, phase=phase,
                              rows_per_block=rows_per_block, **kwargs)
    nx, nv = (n, n) if np.ndim(n) == 0 else (int(n[0]), int(n[1]))
    update, close = reporter(progress, nv, "rows")
    labels = np.full((nv, nx), -1, dtype=np.int64)
    periods = np.zeros((nv, nx), dtype=np.int64)
    last, cancelled = None, False
    try:
        for blk in gen:
            rws = slice(blk.start, blk.start + blk.labels.shape[0])
            labels[rws], periods[rws] = blk.labels, blk.periods
            last = blk
            update(blk.rows_done)
            if stopped(cancel) and blk.rows_done < nv:
                cancelled = True
                break
    finally:
        gen.close()
        close()
    atts = last.attractors if last else ()
    counts = np.bincount(labels[labels >= 0], minlength=len(atts))[:len(atts)]
    total = labels.size
    done = last.rows_done if last else 0
    message = (f"cancelled after {done} of {nv} rows" if cancelled
               else last.message if last else "complete")
    return Basins(params=p, phase=float(phase), x=np.linspace(*x_range, nx),
                          v=np.linspace(*v_range, nv), labels=labels, attractors=atts,
                          fractions=counts / total, undecided=float(np.sum(labels < 0)) / total,
                          periods=periods, complete=bool(done == nv and not cancelled),
                          message=message, elapsed=time.perf_counter() - tic)
