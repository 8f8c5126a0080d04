"""Independent references for the impact oscillator, for tests and the accuracy report.

Nothing here imports the solver (``flight``, ``events``, ``integrators``, ``simulate``):
only :class:`impactlib.model.Params` for the parameter values.

Two references, each returning the first ``n`` impacts (t, v just before impact):

``mp_impacts``  (high precision, the primary reference)
    The closed form of Eq. (1) between impacts, written differently from ``flight.py``:
    the complex characteristic roots lambda of  m l^2 + 2 c l + k = 0,
        distinct:  x_h(s) = Re(A e^{l1 s} + B e^{l2 s})
        repeated:  x_h(s) = (h0 + (hv0 - l h0) s) e^{l s}          (c^2 = k m exactly)
    and the forced part Re(X e^{i w t}) with X = 1 / (k - m w^2 + 2 i c w) in absolute
    time, or t sin(w t) / (2 m w) at exact resonance (c = 0 and m w^2 = k exactly, as
    binary numbers).  Evaluated in mpmath at ``dps`` digits (default 40) from the exact
    binary values of the float inputs; nothing switches formula near critical damping or
    near resonance (the precision absorbs the cancellation).

    Impacts are found by bracketing and refined by a safeguarded Newton iteration in
    mpmath (bisection whenever Newton leaves the bracket) to about 1e-35 relative.  The
    bracketing samples x - g and v on a grid whose step is ``1 / (samples * rate)``,
    rate = max(|l1|, |l2|, w) the fastest time scale of the flight (the step starts
    smaller after a rebound and grows geometrically, so short chatter hops are resolved).
    Besides sign changes of x - g it examines every turning point: each sign change of v
    from - to + (a local minimum of x), and each sampled local minimum of x - g, is refined
    to v = 0 and x - g evaluated there, so a shallow dip below the wall between two samples
    is found however shallow.

    LIMITS (honest): the search is safe when the turning points of x are further apart
    than the sampling step.  Two turning points inside one step (v with a double zero, or
    an extra wiggle faster than 1/rate) can hide a dip; that needs a time scale the rate
    does not account for, which the linear flight does not have away from tangencies
    (leaving the wall at zero force, where x - g ~ tau^3, starts on the wall and is handled
    by starting the samples strictly after the release).  Not a proof, unlike the core's
    Taylor bound: a sampled search, made dense.

    Sticking and chatter ARE handled (the reference needs them for r = 0, preloads and
    the chattering cases): a rebound below ``v_stop`` (default 1e-16) is taken as the end
    of a chatter (the remaining hops last under about 2 v_stop / ((1 - r) |a|), about
    1e-15 for the paper's values, far below any tolerance used; much smaller v_stop would
    need more digits: a hop's height v^2 / (2 |a|) must stay well above the 1e-40
    rounding of x at dps 40); a mass at rest on the wall sticks while the net force
    cos(w t) - k g <= 0 and is released where it crosses zero upwards (arccos in mpmath).
    The impacts of a chatter are all stepped through individually (a few hundred for
    r = 0.8), which is slow but independent of the core's summed tail.

``ivp_impacts``  (scipy, a cross-check with an unrelated integrator)
    ``solve_ivp`` (DOP853, rtol 1e-12, tiny atol) with a terminal event x - g = 0 in the
    direction -1, restarted after each impact with v -> -r v.  Only for orbits without
    grazing, chatter or sticking: it raises :class:`ReferenceNotApplicable` when a
    rebound is too small to restart from, or the mass would stick.  Its global error
    (about 1e-11 to 1e-9 after tens of impacts) makes it a cross-check of ``mp_impacts``
    rather than a 1e-9 reference.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import mpmath
import numpy as np

from ..model import Params

DPS = 40


class ReferenceNotApplicable(RuntimeError):
    """The reference cannot follow this orbit (e.g. chatter or sticking for solve_ivp)."""


@dataclass
class RefResult:
    """First impacts of a reference run.

    t, v : float64 arrays of the impact times and the velocities just before impact.
    t_mp, v_mp : the same in mpmath (``mp_impacts`` only).
    sticking : list of (start, release) floats; start is the accumulation time of the chatter
        (or the impact) that ended on the wall; release may be inf.
    chatter_ends : accumulation times of chatters stepped through to ``v_stop``.
    t_last : time the search reached (the n-th impact, or t_max).
    reason : why it stopped ("n impacts", "t_max", "stuck for good").
    x_end, v_end : the state at t_max when the search got there (reason "t_max").
    """

    t: np.ndarray
    v: np.ndarray
    t_mp: list = field(default_factory=list)
    v_mp: list = field(default_factory=list)
    sticking: list = field(default_factory=list)
    chatter_ends: list = field(default_factory=list)
    t_last: float = 0.0
    reason: str = ""
    x_end: float = math.nan      # state at t_max when the search reached it ("t_max")
    v_end: float = math.nan


# ----------------------------------------------------------------- mpmath closed form


class _System:
    """Constants of Eq. (1) in a private mpmath context."""

    def __init__(self, p: Params, dps: int):
        ctx = mpmath.MPContext()
        ctx.dps = dps
        self.ctx = ctx
        mpf = ctx.mpf
        self.m, self.c, self.k = mpf(p.m), mpf(p.c), mpf(p.k)
        self.g, self.r, self.om = mpf(p.g), mpf(p.r), mpf(p.omega)
        m, c, k, om = self.m, self.c, self.k, self.om
        disc = c * c - k * m              # exact: products of doubles fit in dps 40
        self.repeated = disc == 0
        sq = ctx.sqrt(ctx.mpc(disc))      # complex for underdamped
        self.l1 = (-c + sq) / m
        self.l2 = (-c - sq) / m
        detune = k - m * om * om
        self.resonant = (c == 0) and (detune == 0)
        if not self.resonant:
            X = 1 / ctx.mpc(detune, 2 * c * om)
            self.Xr, self.Xi = X.real, X.imag
        # complex-conjugate roots: x_h = 2 Re(A e^{l1 s}), one exponential
        self.conjugate = disc < 0
        self.rate = float(max(abs(self.l1), abs(self.l2), om))

    # forced part, absolute time; also returns cos(w t) for the acceleration
    def forced(self, t):
        ctx = self.ctx
        om = self.om
        co, si = ctx.cos_sin(om * t)
        if self.resonant:
            d = 2 * self.m * om
            return t * si / d, (si + om * t * co) / d, co
        Xr, Xi = self.Xr, self.Xi
        # Re(X e^{i w t}) and Re(i w X e^{i w t})
        return Xr * co - Xi * si, -om * (Xr * si + Xi * co), co

    def accel(self, t, x, v):
        return (self.ctx.cos(self.om * t) - 2 * self.c * v - self.k * x) / self.m

    def wall_force(self, t):
        return self.ctx.cos(self.om * t) - self.k * self.g

    def release_time(self, t):
        """First time >= t where cos(w t) - k g crosses zero upwards; t if already > 0."""
        ctx = self.ctx
        kg = self.k * self.g
        if kg >= 1:
            return ctx.inf
        if kg < -1 or self.wall_force(t) > 0:
            return t
        theta = 2 * ctx.pi - ctx.acos(kg)
        n = ctx.floor((self.om * t - theta) / (2 * ctx.pi))
        tr = (theta + 2 * ctx.pi * n) / self.om
        while tr < t:
            n += 1
            tr = (theta + 2 * ctx.pi * n) / self.om
        return tr


class _Segment:
    """Free flight from (t0, x0, v0) in mpmath."""

    def __init__(self, S: _System, t0, x0, v0):
        self.S = S
        self.t0 = t0
        self.v0 = v0
        xp, vp, _ = S.forced(t0)
        h0 = x0 - xp
        hv0 = v0 - vp
        if S.repeated:
            lam = S.l1
            self.A = h0
            self.B = hv0 - lam * h0
        else:
            self.A = (hv0 - S.l2 * h0) / (S.l1 - S.l2)
            self.B = h0 - self.A
        if S.conjugate:
            self.Ar, self.Ai = self.A.real, self.A.imag
            self.al, self.be = S.l1.real, S.l1.imag

    def xva(self, t):
        """x, v and x'' (from Eq. 1) at absolute time t."""
        S = self.S
        ctx = S.ctx
        s = t - self.t0
        if S.conjugate:
            # 2 Re(A e^{(al + i be) s}),  A = Ar + i Ai
            ex = 2 * ctx.exp(self.al * s)
            co, si = ctx.cos_sin(self.be * s)
            pr = self.Ar * co - self.Ai * si
            pi = self.Ar * si + self.Ai * co
            xh = ex * pr
            vh = ex * (self.al * pr - self.be * pi)
        elif S.repeated:
            lam = S.l1.real
            e = ctx.exp(lam * s)
            A, B = self.A.real, self.B.real
            xh = (A + B * s) * e
            vh = (B + lam * (A + B * s)) * e
        else:
            e1 = ctx.exp(S.l1 * s)
            e2 = ctx.exp(S.l2 * s)
            xh = ctx.re(self.A * e1 + self.B * e2)
            vh = ctx.re(self.A * S.l1 * e1 + self.B * S.l2 * e2)
        xp, vp, cw = S.forced(t)
        x = xh + xp
        v = vh + vp
        return x, v, (cw - 2 * S.c * v - S.k * x) / S.m

    def xv(self, t):
        x, v, _ = self.xva(t)
        return x, v

    def fva(self, t):
        """x - g, v, a at absolute time t."""
        x, v, a = self.xva(t)
        return x - self.S.g, v, a


def _rtsafe(fun, a, b, fa, fb, tol):
    """Root of fun (returning (value, derivative)) in [a, b] with fa, fb of opposite signs
    (or one zero): Newton, falling back to bisection whenever a step leaves the bracket
    or fails to halve the bracket's worth of progress."""
    if fa == 0:
        return a
    if fb == 0:
        return b
    lo, hi = (a, b) if fa < 0 else (b, a)     # fun(lo) < 0 < fun(hi)
    x = (a + b) / 2
    dx_old = abs(b - a)
    dx = dx_old
    fx, dfx = fun(x)
    for _ in range(400):
        if fx == 0:
            return x
        if fx < 0:
            lo = x
        else:
            hi = x
        newton_ok = dfx != 0
        if newton_ok:
            xn = x - fx / dfx
            newton_ok = (min(lo, hi) < xn < max(lo, hi)) and abs(2 * (xn - x)) <= dx_old
        dx_old = abs(dx)
        if newton_ok:
            dx = xn - x
            x = xn
        else:
            dx = (hi - lo) / 2
            x = lo + dx
        if abs(dx) <= tol or abs(hi - lo) <= tol:
            return x
        fx, dfx = fun(x)
    raise RuntimeError("reference root refinement did not converge")


def _first_impact(seg: _Segment, t_start, t_lim, h_init, h_fast, tol_of, at_wall):
    """First t in (t_start, t_lim] with x(t) = g, or None.  See the module docstring."""
    ctx = seg.S.ctx

    def f_root(t):
        f, v, _ = seg.fva(t)
        return f, v

    def v_root(t):
        _, v, a = seg.fva(t)
        return v, a

    ta = t_start
    fa, va, aa = seg.fva(ta)
    if at_wall:
        # exact start on the wall: x - g = 0 and v = v0 >= 0 (not their rounded re-evaluation)
        fa = ctx.zero
        va = seg.v0
    h = h_init
    prev = None                    # (t, f) of the sample before ta
    while ta < t_lim:
        tb = min(ta + h, t_lim)
        fb, vb, ab = seg.fva(tb)
        if fb <= 0:
            if ta == t_start and at_wall:
                # the hop ended inside the first step: find a point with f > 0 before it
                lo, hi = ta, tb
                for _ in range(200):
                    mid = (lo + hi) / 2
                    fm = seg.fva(mid)[0]
                    if fm > 0:
                        break
                    hi = mid
                else:
                    raise RuntimeError("reference: cannot leave the wall")
                return _rtsafe(f_root, mid, hi, fm, seg.fva(hi)[0], tol_of(hi))
            return _rtsafe(f_root, ta, tb, fa, fb, tol_of(tb))
        # turning point (local minimum of x) inside [ta, tb]
        if va < 0 <= vb:
            tm = _rtsafe(v_root, ta, tb, va, vb, tol_of(tb))
            fm = seg.fva(tm)[0]
            if fm <= 0:
                return _rtsafe(f_root, ta, tm, fa, fm, tol_of(tm))
        elif prev is not None and fa <= prev[1] and fa <= fb and not (ta == t_start and at_wall):
            # a sampled local minimum with no sign change of v seen: refine v = 0 near ta
            tp = prev[0]
            tm = ta
            for _ in range(60):
                _, vm, am = seg.fva(tm)
                if am == 0:
                    break
                step = vm / am
                tm = tm - step
                if not (tp <= tm <= tb):
                    tm = None
                    break
                if abs(step) <= tol_of(tm):
                    break
            if tm is not None:
                fm = seg.fva(tm)[0]
                if fm <= 0:
                    lo = tp if tm < ta else ta
                    flo = prev[1] if tm < ta else fa
                    return _rtsafe(f_root, lo, tm, flo, fm, tol_of(tm))
        prev = (ta, fa)
        ta, fa, va = tb, fb, vb
        h = min(h * 1.25, h_fast)
    return None


def mp_impacts(p: Params, n: int, x0: float | None = None, v0: float = 0.0, t0: float = 0.0,
               t_max: float = math.inf, *, dps: int = DPS, samples: int = 16,
               v_stop: float = 1e-16) -> RefResult:
    """First ``n`` impacts from (x0, v0) at t0, by the closed form in mpmath.

    Parameters
    ----------
    p : Params
    n : int
        Number of impacts wanted (every impact of a chatter counts).
    x0, v0, t0 : float
        Initial state (x0 defaults to max(0, g)); x0 must be >= g.
    t_max : float
        Give up at this time (result's ``reason`` = "t_max").
    dps : int
        mpmath digits.
    samples : int
        Bracketing samples per unit of 1 / rate (see the module docstring).
    v_stop : float
        A rebound below this ends a chatter (the mass is then at rest on the wall).
    """
    S = _System(p, dps)
    ctx = S.ctx
    mpf = ctx.mpf
    x0 = max(0.0, p.g) if x0 is None else x0
    if x0 < p.g:
        raise ValueError(f"x0={x0!r} is behind the wall g={p.g!r}")
    h_fast = mpf(1) / (samples * S.rate)
    tmax = ctx.inf if math.isinf(t_max) else mpf(t_max)
    ulp = mpf(2) ** (-ctx.prec + 6)

    def tol_of(t):
        return ulp * (abs(t) + 1 / S.rate)

    t = mpf(t0)
    x = mpf(x0)
    v = mpf(v0)
    out_t, out_v = [], []
    sticking, chatter_ends = [], []
    reason = "n impacts"
    x_end = v_end = math.nan
    while len(out_t) < n:
        at_wall = x == S.g
        if at_wall and v < 0:
            out_t.append(t)
            out_v.append(v)
            v = -S.r * v
            continue
        if at_wall and v <= v_stop:
            # at rest on the wall (after a plastic impact or a vanished chatter)
            if v > 0:
                chatter_ends.append(float(t))
            v = ctx.zero
            if S.wall_force(t) <= 0:
                tr = S.release_time(t)
                sticking.append((float(t), float(tr)))
                if tr >= tmax:
                    reason = "stuck for good" if ctx.isinf(tr) else "t_max"
                    t = tr
                    x_end, v_end = float(S.g), 0.0
                    break
                t = tr
        seg = _Segment(S, t, x, v)
        if at_wall:
            a0 = S.accel(t, x, v)
            if v > 0 and a0 < 0:
                h_init = min(h_fast, v / (-a0) / samples)
            elif v == 0:
                # leaving from rest: f ~ a s^2 / 2, or ~ F' s^3 / (6 m) at zero force
                h_init = h_fast / samples
            else:
                h_init = min(h_fast, v / S.rate / samples)
        else:
            h_init = h_fast
        ti = _first_impact(seg, t, tmax, h_init, h_fast, tol_of, at_wall)
        if ti is None:
            reason = "t_max"
            t = tmax
            if not ctx.isinf(tmax):
                xe, ve = seg.xv(tmax)
                x_end, v_end = float(xe), float(ve)
            break
        xi, vi = seg.xv(ti)
        if vi > 0:
            vi = ctx.zero                 # a tangency within the refinement tolerance
        out_t.append(ti)
        out_v.append(vi)
        t, x, v = ti, S.g, -S.r * vi
    return RefResult(t=np.array([float(a) for a in out_t]), v=np.array([float(a) for a in out_v]),
                     t_mp=out_t, v_mp=out_v, sticking=sticking, chatter_ends=chatter_ends,
                     t_last=float(t), reason=reason, x_end=x_end, v_end=v_end)


def mp_state(p: Params, ts, x0: float | None = None, v0: float = 0.0, t0: float = 0.0,
             dps: int = DPS):
    """(x, v) at times ts of the FREE flight from (x0, v0) at t0 (no wall), in mpmath,
    returned as float64 arrays."""
    S = _System(p, dps)
    mpf = S.ctx.mpf
    x0 = max(0.0, p.g) if x0 is None else x0
    seg = _Segment(S, mpf(t0), mpf(x0), mpf(v0))
    xs, vs = [], []
    for t in np.asarray(ts, dtype=float):
        x, v = seg.xv(mpf(t))
        xs.append(float(x))
        vs.append(float(v))
    return np.array(xs), np.array(vs)


def mp_release_time(p: Params, t: float, dps: int = DPS) -> float:
    """First time >= t at which a mass at rest on the wall is released (force crosses 0 up)."""
    S = _System(p, dps)
    return float(S.release_time(S.ctx.mpf(t)))


# ----------------------------------------------------------------- scipy solve_ivp


def ivp_impacts(p: Params, n: int, x0: float | None = None, v0: float = 0.0, t0: float = 0.0,
                t_max: float = math.inf, *, rtol: float = 1e-12, atol: float = 1e-15,
                min_rebound: float = 1e-6) -> RefResult:
    """First ``n`` impacts by scipy's DOP853 with a terminal event, restarted at each impact.

    Raises ReferenceNotApplicable when the orbit chatters or sticks: a rebound below
    ``min_rebound`` times the largest impact speed so far, a rebound of zero (r = 0) with
    the force pushing into the wall, or two impacts closer than 1e-9 of the rate's scale.
    ``max_step`` is 0.5 / rate so that the event check sees every dip of the linear flow's
    own time scales (grazing orbits are out of scope; see mp_impacts).
    """
    from scipy.integrate import solve_ivp

    m, c, k, g, r, om = p.m, p.c, p.k, p.g, p.r, p.omega
    a = c / m
    w0sq = k / m
    rate = max(a + math.sqrt(a * a - w0sq) if a * a > w0sq else math.sqrt(w0sq), om)
    x0 = max(0.0, g) if x0 is None else x0

    def rhs(t, y):
        return [y[1], (math.cos(om * t) - 2.0 * c * y[1] - k * y[0]) / m]

    def event(t, y):
        return y[0] - g

    event.terminal = True
    event.direction = -1

    t_end = t0 + 1e6 / rate if math.isinf(t_max) else t_max
    t, y = float(t0), [float(x0), float(v0)]
    out_t, out_v = [], []
    vmax = 0.0
    reason = "n impacts"
    while len(out_t) < n:
        if y[0] == g and y[1] == 0.0 and math.cos(om * t) - k * g <= 0.0:
            raise ReferenceNotApplicable(f"solve_ivp reference: the mass sticks at t={t:.17g}")
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol,
                        events=event, max_step=0.5 / rate)
        if sol.status == -1:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        if sol.status == 0:
            reason = "t_max"
            t = t_end
            break
        te = float(sol.t_events[0][0])
        ve = float(sol.y_events[0][0][1])
        if te - t <= 1e-9 / rate and out_t:
            raise ReferenceNotApplicable(f"solve_ivp reference: chatter at t={te:.17g}")
        ve = min(ve, 0.0)
        out_t.append(te)
        out_v.append(ve)
        vmax = max(vmax, -ve)
        vplus = -r * ve
        if 0.0 < vplus < min_rebound * vmax:
            raise ReferenceNotApplicable(f"solve_ivp reference: chatter at t={te:.17g}")
        t, y = te, [g, vplus]
    return RefResult(t=np.array(out_t), v=np.array(out_v), t_last=t, reason=reason)


__all__ = ["RefResult", "ReferenceNotApplicable", "mp_impacts", "mp_state", "mp_release_time",
           "ivp_impacts"]
