"""Pseudo-arclength continuation of impacting periodic orbits, with their bifurcations.

Unknowns that stay smooth
-------------------------
An orbit with m impacts in n forcing periods is described by its impact times
t_1 < ... < t_m and the velocities u_1, ..., u_m (< 0) just before them, as in the
multi-segment boundary-value formulation of COCO's impact oscillator (Dankowicz &
Schilder, Recipes for Continuation, SIAM 2013, Ex. 15.2: one trajectory segment per
flight, glued by the impact law).  Flight j starts at (g, -r u_j) at t_j and must arrive at
(g, u_{j+1}) at t_{j+1} (t_{m+1} = t_1 + n T, u_{m+1} = u_1):

    F_{2j}   = x(t_{j+1}; t_j, g, -r u_j) - g = 0,
    F_{2j+1} = v(t_{j+1}; t_j, g, -r u_j) - u_{j+1} = 0.

x and v are the closed form of :mod:`impactlib.flight`, smooth in (t_j, u_j, t_{j+1}) and
in the parameters, also as u_j -> 0, where the stroboscopic map's Jacobian blows up like
1/|u| (grazing).  Derivatives: d/dt_{j+1} = (v, a) at the arrival; d/du_j = -r Phi(s)[:, 1];
d/dt_j = -Phi(s) f(t_j, y_j) (a later start at the same state); d/dparameter by central
differences of F.  The 2m equations in 2m + 1 unknowns (with the parameter) define the
branch, followed by Keller's pseudo-arclength method (predictor along the tangent, Newton
corrector on [F; tangent . (z - z_pred)]), so folds are passed.

Multipliers and test functions
------------------------------
The monodromy matrix is M = S_1 Phi(s_m) S_m ... S_2 Phi(s_1) (cyclic, the same
eigenvalues as the stroboscopic map).  With S_j = [[-r, 0], [sigma_j / u_j, -r]],
u_j S_j is smooth, so with P = prod u_j the matrix M~ = P M is smooth and so are

    period doubling (a multiplier through -1):   phi_PD = (-1)^m [P (1 + det M) + tr M~]
    saddle-node (a multiplier through +1):        phi_SN = (-1)^m [P (1 + det M) - tr M~]

(the characteristic polynomial at -1 and +1 times |P|), which keep their sign through
u_j -> 0.  A Neimark-Sacker point needs det M = 1, but det M = r^(2m) e^{-2 c n T / m}
< 1 whenever there is dissipation: it can occur only with c = 0 and r = 1; its test
function det M - 1 is watched on complex pairs.  Grazing: max_j u_j crosses 0 (an impact
at zero speed), or the lowest point of a flight between impacts reaches the wall.  Each
event is located by Illinois false position on the arclength of the step where its test
function changed sign.

Period doubling to n = 2: at a period doubling the period-n orbit, counted as a
2n-period orbit, is a branch point of the 2n-period problem (its Jacobian gains a null
vector).  :func:`continuation` started there with the doubled n steps off along that
null vector onto the doubled branch (branch switching as in Kuznetsov, Elements of
Applied Bifurcation Theory, 3rd ed., ch. 10).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..kernels._jit import jit
from ..kernels.flight import G, K, M, OM, R, C_, flight_state, start_segment, system_constants
from ..kernels.grazing import CLEARANCE_SAMPLES, lowest_in_flight
from ..model import Params
from .orbits import check_start, periodic_orbit
from ..kernels.tangent import flow_jacobian
from ..io.result import SweepResult

NEWTON_TOL = 1e-11
NEWTON_MAX = 8
EVENT_KINDS = ("period-doubling", "saddle-node", "neimark-sacker", "grazing")
MU_STEP = 0.2          # largest change of a multiplier per step while one is below MU_WATCH
MU_WATCH = 3.0


@jit
def segments_residual(sp, ts, us, total, F, DF):
    """Residual F (2m,) of the multi-segment problem and its Jacobian DF (2m, 2m) with
    respect to (t_1..t_m, u_1..u_m); total = n T."""
    m = ts.shape[0]
    g = sp[G]
    r = sp[R]
    mass = sp[M]
    for i in range(2 * m):
        for j in range(2 * m):
            DF[i, j] = 0.0
    for j in range(m):
        jn = j + 1 if j + 1 < m else 0
        t0 = ts[j]
        t1 = ts[jn] if j + 1 < m else ts[0] + total
        v0 = -r * us[j]
        seg = start_segment(sp, t0, g, v0)
        s = t1 - t0
        x, v, a, jerk, rh, xs = flight_state(sp, seg, s)
        F[2 * j] = x - g
        F[2 * j + 1] = v - us[jn]
        p11, p12, p21, p22 = flow_jacobian(sp, s)
        # arrival time
        DF[2 * j, jn] += v
        DF[2 * j + 1, jn] += a
        # start velocity
        DF[2 * j, m + j] += -r * p12
        DF[2 * j + 1, m + j] += -r * p22
        # start time at a fixed start state: -Phi f(t0, y0)
        a0 = (math.cos(sp[OM] * t0) - 2.0 * sp[C_] * v0 - sp[K] * g) / mass
        DF[2 * j, j] += -(p11 * v0 + p12 * a0)
        DF[2 * j + 1, j] += -(p21 * v0 + p22 * a0)
        DF[2 * j + 1, m + jn] += -1.0


@jit
def segments_monodromy(sp, ts, us, total):
    """(M~ = P M as m11, m12, m21, m22;  P = prod u_j;  det M) of the orbit."""
    m = ts.shape[0]
    r = sp[R]
    mass = sp[M]
    a11, a12, a21, a22 = 1.0, 0.0, 0.0, 1.0
    prod_u = 1.0
    for j in range(m):
        jn = j + 1 if j + 1 < m else 0
        t1 = ts[jn] if j + 1 < m else ts[0] + total
        p11, p12, p21, p22 = flow_jacobian(sp, t1 - ts[j])
        b11 = p11 * a11 + p12 * a21
        b12 = p11 * a12 + p12 * a22
        b21 = p21 * a11 + p22 * a21
        b22 = p21 * a12 + p22 * a22
        # u S at the arrival impact (time t1, velocity u_jn): [[-r u, 0], [sigma, -r u]]
        u = us[jn]
        sigma = (1.0 + r) * (math.cos(sp[OM] * t1) - sp[K] * sp[G]) / mass
        a11 = -r * u * b11
        a12 = -r * u * b12
        a21 = sigma * b11 - r * u * b21
        a22 = sigma * b12 - r * u * b22
        prod_u *= u
    det_m = r ** (2 * m) * math.exp(-2.0 * sp[C_] / mass * total)
    return a11, a12, a21, a22, prod_u, det_m


@jit
def segments_clearance(sp, ts, us, total, nsamp):
    """Lowest interior minimum of x - g over the flights (inf when no flight dips), each
    flight's from :func:`impactlib.kernels.grazing.lowest_in_flight`."""
    m = ts.shape[0]
    g = sp[G]
    r = sp[R]
    best = math.inf
    for j in range(m):
        t1 = ts[j + 1] if j + 1 < m else ts[0] + total
        seg = start_segment(sp, ts[j], g, -r * us[j])
        best = min(best, lowest_in_flight(sp, seg, t1 - ts[j], math.nan, nsamp)[0])
    return best


@jit
def segments_section(sp, ts, us, total, t_sec):
    """State (x, v) of the orbit at time t_sec (any time; reduced into the cycle)."""
    m = ts.shape[0]
    g = sp[G]
    r = sp[R]
    t = ts[0] + ((t_sec - ts[0]) - total * math.floor((t_sec - ts[0]) / total))
    j = m - 1
    for i in range(m - 1):
        if ts[i] <= t < ts[i + 1]:
            j = i
            break
    seg = start_segment(sp, ts[j], g, -r * us[j])
    x, v, a, jk, rh, xs = flight_state(sp, seg, t - ts[j])
    return x, v


class Event(tuple):
    """An event of a branch: a (kind, value) pair with the orbit there.

    kind : "period-doubling", "saddle-node", "neimark-sacker" or "grazing".
    value : the continuation parameter at the event (located to ~1e-9).
    params : Params at the event; x, v : the orbit's state on the section there;
    multipliers : (2,) complex there; index : its position in the branch arrays.
    name, n, phase : the branch's parameter, periods and section (None when built by hand).
    impact_times, impact_velocities : (m,) the orbit's unknowns there (None when built by
    hand); :func:`impactlib.boundary` starts from them.
    """

    def __new__(cls, kind, value, params, x, v, multipliers, index, name=None, n=None,
                phase=None, impact_times=None, impact_velocities=None):
        obj = super().__new__(cls, (kind, float(value)))
        obj.kind, obj.value, obj.params = kind, float(value), params
        obj.x, obj.v, obj.multipliers, obj.index = float(x), float(v), multipliers, index
        obj.name, obj.n, obj.phase = name, n, phase
        obj.impact_times, obj.impact_velocities = impact_times, impact_velocities
        return obj

    def __reduce__(self):
        return (Event, (self.kind, self.value, self.params, self.x, self.v,
                        self.multipliers, self.index, self.name, self.n, self.phase,
                        self.impact_times, self.impact_velocities))


@dataclass(frozen=True, repr=False, eq=False)
class Branch(SweepResult):
    """Result of :func:`continuation`: one entry per point along the branch (located
    events included, in order).

    Attributes
    ----------
    name : str
        The continued parameter.
    n : int
        Forcing periods per orbit.
    impacts : int
        Impacts per orbit (m).
    phase : float
        The section (s).
    param, x, v : ndarray, shape (k,)
        The parameter and the orbit's state on the section t = phase.
    multipliers : ndarray of complex, shape (k, 2)
        Largest modulus first.
    stable, admissible : ndarray of bool, shape (k,)
    events : list of Event
        Each a (kind, value) pair.
    impact_times, impact_velocities : ndarray, shape (k, m)
        The unknowns of each point (s; velocity before impact).
    message : str
        Why the branch ended.
    start : PeriodicOrbit
        The orbit the branch started from (its ``params`` are the fixed parameters).
    """

    name: str
    n: int
    impacts: int
    phase: float
    param: np.ndarray
    x: np.ndarray
    v: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    admissible: np.ndarray
    events: list
    impact_times: np.ndarray
    impact_velocities: np.ndarray
    message: str
    start: object = field(default=None, repr=False)


class _Problem:
    """The multi-segment problem of one orbit type at one set of fixed parameters."""

    def __init__(self, p: Params, name: str, n: int, m: int, phase: float):
        self.p, self.name, self.n, self.m, self.phase = p, name, n, m, phase
        self.F = np.empty(2 * m)
        self.DF = np.empty((2 * m, 2 * m))
        self._cache = {}

    def params(self, lam):
        return self.p.replace(**{self.name: float(lam)})

    def sp(self, lam):
        sp = self._cache.get(lam)
        if sp is None:
            q = self.params(lam)       # raises ValueError outside the valid range
            sp = (system_constants(q.m, q.c, q.k, q.g, q.r, q.omega), self.n * q.T)
            if len(self._cache) > 8:
                self._cache.clear()
            self._cache[lam] = sp
        return sp

    def residual(self, z):
        m = self.m
        sp, total = self.sp(z[-1])
        segments_residual(sp, z[:m], z[m:2 * m], total, self.F, self.DF)
        return self.F.copy()

    def jacobian(self, z):
        """(F, DF_z) with the parameter column by central differences."""
        m = self.m
        lam = z[-1]
        sp, total = self.sp(lam)
        segments_residual(sp, z[:m], z[m:2 * m], total, self.F, self.DF)
        F = self.F.copy()
        J = np.empty((2 * m, 2 * m + 1))
        J[:, :2 * m] = self.DF
        h = 1e-6 * max(1.0, abs(lam))
        zp = z.copy()
        zp[-1] = lam + h
        zm = z.copy()
        zm[-1] = lam - h
        try:
            fp = self.residual(zp)
        except ValueError:      # at the edge of the valid range: one-sided
            fp, zp = F, z
        try:
            fm = self.residual(zm)
        except ValueError:
            fm, zm = F, z
        J[:, -1] = (fp - fm) / (zp[-1] - zm[-1])
        return F, J

    def describe(self, z):
        """(x, v, multipliers, stable, admissible, tests) at a point."""
        m = self.m
        sp, total = self.sp(z[-1])
        ts, us = z[:m], z[m:2 * m]
        x, v = segments_section(sp, ts, us, total, self.phase)
        a11, a12, a21, a22, P, det = segments_monodromy(sp, ts, us, total)
        if P != 0.0:
            Mx = np.array([[a11, a12], [a21, a22]]) / P
            mu = np.linalg.eigvals(Mx).astype(complex)
            mu = mu[np.argsort(-np.abs(mu), kind="stable")]
        else:
            mu = np.array([complex(math.inf), complex(0.0)])
        tr = a11 + a22
        sgn = -1.0 if m % 2 else 1.0
        phi_pd = sgn * (P * (1.0 + det) + tr)
        phi_sn = sgn * (P * (1.0 + det) - tr)
        complex_pair = bool(np.all(np.abs(mu.imag) > 0))
        phi_ns = det - 1.0 if complex_pair else math.nan
        clearance = segments_clearance(sp, ts, us, total, CLEARANCE_SAMPLES)
        graze = min(-float(np.max(us)), clearance)
        tests = {"period-doubling": phi_pd, "saddle-node": phi_sn, "neimark-sacker": phi_ns,
                 "grazing": graze}
        admissible = bool(graze > 0.0)
        stable = bool(np.all(np.abs(mu) < 1.0))
        return x, v, mu, stable, admissible, tests


def _null_tangent(J, t_prev=None):
    """Unit tangent: the null vector of J (2m x (2m+1)), oriented along t_prev."""
    q, _ = np.linalg.qr(J.T, mode="complete")
    t = q[:, -1]
    if t_prev is not None and float(t @ t_prev) < 0.0:
        t = -t
    return t / np.linalg.norm(t)


def _correct(prob, z_pred, t_dir, s_target=None, z_base=None):
    """Newton on [F(z); t_dir . (z - z_base) - s_target] (or t_dir . (z - z_pred) = 0)."""
    z = z_pred.copy()
    base = z_pred if z_base is None else z_base
    s = 0.0 if s_target is None else s_target
    nz = z.size
    A = np.empty((nz, nz))
    b = np.empty(nz)
    for it in range(1, NEWTON_MAX + 1):
        try:
            F, J = prob.jacobian(z)
        except ValueError:
            return None, it
        A[:-1] = J
        A[-1] = t_dir
        b[:-1] = F
        b[-1] = t_dir @ (z - base) - s
        try:
            dz = np.linalg.solve(A, -b)
        except np.linalg.LinAlgError:
            return None, it
        if not np.all(np.isfinite(dz)):
            return None, it
        z = z + dz
        if np.max(np.abs(dz)) <= 1e-12 * (1.0 + np.max(np.abs(z))):
            try:
                F = prob.residual(z)
            except ValueError:
                return None, it
            if np.max(np.abs(F)) <= NEWTON_TOL * (1.0 + np.max(np.abs(z))):
                return z, it
    try:
        F = prob.residual(z)
    except ValueError:
        return None, NEWTON_MAX
    if np.max(np.abs(F)) <= NEWTON_TOL * (1.0 + np.max(np.abs(z))):
        return z, NEWTON_MAX
    return None, NEWTON_MAX


def _locate(prob, z0, t0, s_hi, kind, f_lo, f_hi):
    """The point of the step (z0, t0, arclength s_hi) where test ``kind`` is zero."""
    return locate_on_step(lambda s: _correct(prob, z0 + s * t0, t0, s, z0)[0],
                          lambda z: prob.describe(z)[5][kind], s_hi, f_lo, f_hi)


def locate_on_step(point_at, test, s_hi, f_lo, f_hi):
    """The point of a continuation step where ``test`` changes sign: Illinois false
    position in the arclength s in (0, s_hi), ``point_at(s)`` the corrected point there
    (None where the corrector fails; then the midpoint is tried once)."""
    lo, hi = 0.0, s_hi
    z_best = None
    side = 0
    for _ in range(60):
        s = (lo * f_hi - hi * f_lo) / (f_hi - f_lo) if f_hi != f_lo else 0.5 * (lo + hi)
        if not (lo < s < hi):
            s = 0.5 * (lo + hi)
        z = point_at(s)
        if z is None:
            s = 0.5 * (lo + hi)
            z = point_at(s)
            if z is None:
                break
        fs = test(z)
        z_best = z
        if fs == 0.0 or not math.isfinite(fs):
            break
        if (fs > 0) == (f_lo > 0):
            lo, f_lo = s, fs
            if side == 1:
                f_hi *= 0.5
            side = 1
        else:
            hi, f_hi = s, fs
            if side == -1:
                f_lo *= 0.5
            side = -1
        if hi - lo <= 1e-11 * (1.0 + abs(s_hi)):
            break
    return z_best


def stop_problems(p, name: str, stop: float) -> list[str]:
    """What is wrong with following parameter ``name`` of ``p`` to the finite ``stop``."""
    start = getattr(p, name)
    if stop == start:
        return [f"stop={stop!r} equals the start value {name}={start!r}"]
    try:
        p.replace(**{name: stop})
    except ValueError as err:
        return [f"stop={stop!r} is outside the valid range of {name} "
                f"({str(err).removeprefix('invalid parameters: ')})"]
    return []


def ds_problems(ds) -> list[str]:
    """What is wrong with a continuation step ``ds`` (None: the default step)."""
    if ds is None:
        return []
    try:
        ok = not isinstance(ds, bool) and math.isfinite(float(ds)) and float(ds) > 0
    except (TypeError, ValueError):
        ok = False
    return [] if ok else [f"ds={ds!r} must be a positive number"]


def _check_branch(p, name, stop, n, x0, v0, phase, ds, max_points):
    check_start(p, name, n, x0, v0, phase)
    problems = []
    try:
        stop_f = float(stop)
    except (TypeError, ValueError):
        raise ValueError(f"invalid branch: stop={stop!r} is not a number") from None
    if not math.isfinite(stop_f):
        problems.append(f"stop={stop!r} is not finite")
    else:
        problems += stop_problems(p, name, stop_f)
    problems += ds_problems(ds)
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)) or max_points < 2:
        problems.append(f"max_points={max_points!r} must be a whole number >= 2")
    if problems:
        raise ValueError("invalid branch: " + "; ".join(problems))
    return stop_f


def continuation(p: Params, name: str, stop: float, n: int = 1, x0: float | None = None,
                 v0: float | None = None, phase: float = 0.0, ds: float | None = None,
                 max_points: int = 2000) -> Branch:
    """Follow a periodic orbit as parameter ``name`` moves from its value in ``p`` to ``stop``.

    Pseudo-arclength continuation of the multi-segment problem (see the module notes),
    through folds (the parameter may turn back), with the events located where a
    multiplier crosses -1 (period-doubling), +1 (saddle-node) or the unit circle
    (neimark-sacker), and where the orbit grazes (an impact speed reaches 0, or a flight
    touches the wall between impacts).  The branch stops at a grazing (beyond it the
    orbit is no longer a motion of the oscillator), at ``stop``, after ``max_points``,
    or where the corrector fails with the smallest step; ``message`` says which.

    Parameters
    ----------
    p : Params
        Start parameters; the orbit is found by :func:`impactlib.periodic_orbit`.
    name : one of "m", "c", "k", "g", "r", "omega"
    stop : float
        Target value of the parameter.
    n, x0, v0, phase : as in :func:`impactlib.periodic_orbit`.  Started at a
        period-doubling event of an n/2 branch (x0, v0 = event.x, event.v and p =
        event.params), the branch switches onto the doubled orbit.
    ds : float, optional
        First arclength step (default ``abs(stop - start) / 100``); adapted on the way.
    max_points : int

    Returns
    -------
    Branch
    """
    stop = _check_branch(p, name, stop, n, x0, v0, phase, ds, max_points)
    n = int(n)
    lam0 = getattr(p, name)
    span = abs(stop - lam0)
    ds = span / 100.0 if ds is None else float(ds)
    ds_min = 1e-9 * max(1.0, span)
    orb = periodic_orbit(p, n, x0, v0, phase)
    trace = _Trace(name, n, float(phase), orb)
    refusal = _refusal(orb)
    if refusal:
        return trace.branch(0, refusal)
    prob = _Problem(p, name, n, int(orb.impacts), float(phase))
    z, J = _polished_start(prob, orb, lam0)
    # the arclength counts the unknowns too: they may move much faster than the parameter
    steps = _Steps(ds, ds_min, max(ds, span / 15.0, float(np.linalg.norm(z[:-1])) / 15.0))
    trace.problem = prob
    tests = trace.add(z)
    z, t, tests = _first_tangent(prob, trace, z, J, tests, steps.ds,
                                 math.copysign(1.0, stop - lam0))
    message = _follow(prob, trace, z, t, tests, stop, steps, max_points)
    return trace.branch(prob.m, message)


def _refusal(orb) -> str:
    """Why the orbit ``orb`` cannot start a branch ("" if it can)."""
    if not orb.converged:
        return f"no periodic orbit to start from: {orb.message}"
    if orb.sticks:
        return ("the orbit sticks to the wall: its branch has no smooth impact "
                "unknowns to follow (multipliers 0)")
    if int(orb.impacts) == 0:
        return "the orbit has no impact: the multi-segment problem needs impacts"
    return ""


def _polished_start(prob, orb, lam0):
    """The start z = (impact times, impact velocities, parameter) and its Jacobian,
    polished on the multi-segment problem (periodic_orbit converged it to ~1e-12)."""
    z = np.concatenate([orb.impact_times, orb.impact_velocities, [lam0]])
    F, J = prob.jacobian(z)
    if np.max(np.abs(F)) > 1e-10:
        for _ in range(NEWTON_MAX):
            z[:-1] -= np.linalg.lstsq(J[:, :-1], F, rcond=None)[0]
            F, J = prob.jacobian(z)
            if np.max(np.abs(F)) <= 1e-12:
                break
    return z, J


class _Trace:
    """The points and events of a branch as it is followed, and the Branch they make."""

    def __init__(self, name, n, phase, orb):
        self.name, self.n, self.phase, self.orb = name, n, phase, orb
        self.problem = None
        self.points = []        # (z, x, v, multipliers, stable, admissible)
        self.events = []

    def add(self, z):
        """Append the point z; return its test functions."""
        x, v, mu, st, adm, tests = self.problem.describe(z)
        self.points.append((z.copy(), x, v, mu, st, adm))
        return tests

    def add_event(self, kind, z):
        """Append the point z of an event of ``kind`` and the Event itself."""
        self.add(z)
        prob, m = self.problem, self.problem.m
        _, x, v, mu = self.points[-1][:4]
        self.events.append(Event(kind, z[-1], prob.params(z[-1]), x, v, mu,
                                 len(self.points) - 1, self.name, self.n, self.phase,
                                 z[:m].copy(), z[m:2 * m].copy()))

    def branch(self, m, message) -> Branch:
        pts = self.points
        if not pts:
            c = np.empty(0)
            return Branch(self.name, self.n, 0, self.phase, c, c, c, np.empty((0, 2), complex),
                          np.empty(0, bool), np.empty(0, bool), [], np.empty((0, 0)),
                          np.empty((0, 0)), message, self.orb)
        zs = np.array([q[0] for q in pts])
        return Branch(name=self.name, n=self.n, impacts=m, phase=self.phase,
                      param=zs[:, -1].copy(), x=np.array([q[1] for q in pts]),
                      v=np.array([q[2] for q in pts]),
                      multipliers=np.array([q[3] for q in pts]),
                      stable=np.array([q[4] for q in pts]),
                      admissible=np.array([q[5] for q in pts]), events=self.events,
                      impact_times=zs[:, :m].copy(), impact_velocities=zs[:, m:2 * m].copy(),
                      message=message, start=self.orb)


def _first_tangent(prob, trace, z, J, tests, ds, direction):
    """(z, t, tests) to step from: the tangent at the start pointing towards ``stop``,
    or, at a period-doubling point of the n/2 orbit started as an n orbit, the first
    point and tangent of the doubled branch (a branch switch)."""
    n = prob.n
    sv = np.linalg.svd(J[:, :-1], compute_uv=False)
    if n % 2 == 0 and sv[-1] < 1e-7 * sv[0]:
        _, _, vt = np.linalg.svd(J[:, :-1])
        nu = np.concatenate([vt[-1], [0.0]])
        z1, _ = _correct(prob, z + ds * nu, nu, ds, z)
        if z1 is not None:
            _, J1 = prob.jacobian(z1)
            t = _null_tangent(J1, z1 - z)
            return z1, t, trace.add(z1)
    t = _null_tangent(J)
    if t[-1] * direction < 0:
        t = -t
    return z, t, tests


class _Steps:
    """The arclength step: halved on a failed or too large step, grown after easy ones."""

    def __init__(self, ds, ds_min, ds_max):
        self.ds, self.ds_min, self.ds_max = ds, ds_min, ds_max

    @property
    def smallest(self) -> bool:
        return self.ds <= self.ds_min

    def halve(self):
        self.ds = max(0.5 * self.ds, self.ds_min)

    def adapt(self, newton_iterations):
        if newton_iterations <= 3:
            self.ds = min(self.ds * 1.4, self.ds_max)
        elif newton_iterations >= 6:
            self.ds = max(self.ds * 0.6, self.ds_min)


def _predict_correct(prob, z, t, stop, steps):
    """One predictor-corrector step from (z, t): (z_new, t_new, iterations, at_stop),
    z_new None where the corrector failed or the tangent turned too far. A step that
    reaches ``stop`` lands on it (Newton at the fixed parameter value)."""
    ds = steps.ds
    lam_pred = z[-1] + ds * t[-1]
    at_stop = (z[-1] - stop) * (lam_pred - stop) <= 0.0 and t[-1] != 0.0
    if at_stop:
        frac = (stop - z[-1]) / (ds * t[-1])
        e_lam = np.zeros(z.size)
        e_lam[-1] = 1.0
        z_new, its = _correct(prob, z + frac * ds * t, e_lam, stop, np.zeros(z.size))
    else:
        z_new, its = _correct(prob, z + ds * t, t, ds, z)
    t_new = None
    if z_new is not None:
        _, Jn = prob.jacobian(z_new)
        t_new = _null_tangent(Jn, t)
        if float(t_new @ t) < 0.98 and not steps.smallest:
            z_new = None
    return z_new, t_new, its, at_stop


def _multipliers_jump(mu, mu_prev, steps) -> bool:
    """Multipliers near the unit circle must move little per step, so that no pair of
    events (a stability change and its reversal) hides inside one step."""
    return bool(not steps.smallest and np.max(np.abs(mu - mu_prev)) > MU_STEP
                and min(np.max(np.abs(mu)), np.max(np.abs(mu_prev))) < MU_WATCH)


def _events_in_step(prob, z, t, z_new, tests_prev, tests):
    """The events whose test changes sign between z and z_new, located on the step, in
    the order they occur along it: [(arclength, kind, point)]."""
    s_step = float(t @ (z_new - z))
    found = []
    for kind in EVENT_KINDS:
        a, b = tests_prev[kind], tests[kind]
        if math.isfinite(a) and math.isfinite(b) and (a > 0) != (b > 0) and a != 0.0:
            ze = _locate(prob, z, t, s_step, kind, a, b)
            if ze is not None:
                found.append((float(t @ (ze - z)), kind, ze))
    found.sort(key=lambda e: e[0])
    return found


def _follow(prob, trace, z, t, tests_prev, stop, steps, max_points) -> str:
    """Step along the branch from (z, t) until ``stop``, a grazing, ``max_points`` or a
    failure at the smallest step; the points and events go to ``trace``. Returns the
    branch's message."""
    name = prob.name
    while len(trace.points) < max_points:
        z_new, t_new, its, at_stop = _predict_correct(prob, z, t, stop, steps)
        if z_new is None:
            if steps.smallest:
                try:
                    prob.params(z[-1] + steps.ds_min * t[-1])
                    return "the corrector failed at the smallest step"
                except ValueError:
                    return f"reached the edge of the valid range of {name}"
            steps.halve()
            continue
        _, _, mu, _, _, tests = prob.describe(z_new)
        if _multipliers_jump(mu, trace.points[-1][3], steps):
            steps.halve()
            continue
        for _, kind, ze in _events_in_step(prob, z, t, z_new, tests_prev, tests):
            trace.add_event(kind, ze)
            if kind == "grazing":
                return f"stopped at grazing, {name} = {ze[-1]:.10g}"
        tests_prev = trace.add(z_new)
        if at_stop:
            return f"reached {name} = {stop:g}"
        z, t = z_new, t_new
        steps.adapt(its)
    return f"reached max_points={max_points}"
