"""Periodic orbits of the stroboscopic map and their Floquet multipliers.

The n-period stroboscopic map P^n takes the state (x, v) at t = phase to the state at
t = phase + n T along the exact motion.  Its Jacobian is the product of flow Jacobians
and saltation matrices along the orbit (see :mod:`impactlib.tangent`), so Newton's method
on P^n(z) - z = 0 converges quadratically to stable and unstable orbits alike, and the
eigenvalues of the converged Jacobian are the orbit's Floquet multipliers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels import engine as E
from ..model import PARAM_NAMES, Params, RunLimits
from ..simulate import run_constants, simulate
from ..io.result import Result

NEWTON_MAX = 40
NEWTON_TOL = 1e-11          # residual, relative to the orbit's size (and 1)
SETTLE_TIME = 250.0         # the paper's transient
IMPACT_CAP = 4096


@dataclass(frozen=True, repr=False, eq=False)
class PeriodicOrbit(Result):
    """Result of :func:`periodic_orbit`.

    Units: x in length, v in length per time unit, times in s.

    Attributes
    ----------
    params : Params
    x, v : float
        The orbit's state on the section t = phase (mod T).
    n : int
        Forcing periods per orbit.
    phase : float
        The section (s).
    impacts : float
        Impacts per orbit (the paper's m; inf for a chatter summed to its accumulation point).
    label : str
        The paper's "m-impact period-n" name.
    multipliers : ndarray of complex, shape (2,)
        Eigenvalues of the n-period map's Jacobian, largest modulus first; both 0 for an
        orbit that sticks (its Jacobian vanishes).
    stable : bool
        Every ``abs(multiplier) < 1``.
    admissible : bool
        Never below the wall between impacts.
    converged : bool
        Newton's outcome.
    residual : float
        ``max(abs(P^n(z) - z))`` at the returned point.
    sticks : bool
        The orbit rests on the wall for a while in each cycle.
    iterations : int
        Newton steps taken.
    message : str
        Newton's outcome in words.
    impact_times, impact_velocities : ndarray
        The impacts of one cycle from t = phase (s; velocity before impact, < 0).
    jacobian : ndarray, shape (2, 2)
        Jacobian of the n-period map.
    """

    params: Params
    x: float
    v: float
    n: int
    phase: float
    impacts: float
    label: str
    multipliers: np.ndarray
    stable: bool
    admissible: bool
    converged: bool
    residual: float
    sticks: bool
    iterations: int
    message: str
    impact_times: np.ndarray
    impact_velocities: np.ndarray
    jacobian: np.ndarray


def check_start(p, name, n, x0, v0, phase):
    """One ValueError naming every bad field of an orbit or branch start."""
    problems = []
    if not isinstance(p, Params):
        raise TypeError(f"p must be impactlib.Params, got {type(p).__name__}")
    if name is not None and name not in PARAM_NAMES:
        problems.append(f"name={name!r} is not a parameter; expected one of {', '.join(PARAM_NAMES)}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        problems.append(f"n={n!r} must be a whole number >= 1")
    for fld, val in (("x0", x0), ("v0", v0)):
        if val is not None:
            try:
                f = float(val)
            except (TypeError, ValueError):
                problems.append(f"{fld}={val!r} is not a number")
                continue
            if not math.isfinite(f):
                problems.append(f"{fld}={f!r} is not finite")
            elif fld == "x0" and f < p.g:
                problems.append(f"x0={f!r} is behind the endstop g={p.g!r} (need x0 >= g)")
    try:
        ph = float(phase)
        if not math.isfinite(ph) or not (0.0 <= ph <= p.T):
            problems.append(f"phase={phase!r} must lie in [0, T={p.T!r}] (time units)")
    except (TypeError, ValueError):
        problems.append(f"phase={phase!r} is not a number")
    if problems:
        raise ValueError("invalid start: " + "; ".join(problems))


class MapEval:
    """The n-period stroboscopic map with its Jacobian, by the exact kernels."""

    def __init__(self, p: Params, n: int, phase: float):
        self.p = p
        self.sp, self.rate, self.hmax = run_constants(p)
        self.t0 = phase
        self.t1 = phase + n * p.T
        self.imp_t = np.empty(IMPACT_CAP)
        self.imp_v = np.empty(IMPACT_CAP)
        self.buffers = E.buffers(imp_t=self.imp_t, imp_v=self.imp_v)
        lim = RunLimits()
        self.ctl = E.controls(self.t1, self.t0, self.hmax, self.rate, 0.0, 0.0, 0.0,
                              lim.max_impacts, lim.max_steps, E.EXACT, E.JACOBIAN)
        self.res = np.empty(E.NRES)

    def __call__(self, x, v):
        """(x1, v1, J, info): the state one map later, the Jacobian as floats (j11, j12,
        j21, j22), info = (status, n_impacts, stuck, vmin, n_rec, n_tail)."""
        x = max(x, self.p.g)
        res = self.res
        status = E.run_engine(self.sp, self.ctl, self.t0, x, v, self.buffers, res)
        out = res.tolist()      # Python floats: Newton's 2 x 2 algebra runs on them
        # a mass that sticks at some point of the cycle: the map is locally constant
        sticks = out[E.STUCK] != 0.0 or out[E.STUCK_MARKED] != 0.0
        return (out[E.X_F], out[E.V_F], tuple(out[E.J11:E.J22 + 1]),
                (status, int(out[E.N_TOT]), sticks, out[E.VMIN], int(out[E.N_REC]),
                 int(out[E.N_TAIL])))

    def impacts(self, n_rec):
        k = min(n_rec, IMPACT_CAP)
        return self.imp_t[:k].copy(), self.imp_v[:k].copy()


def settle_starts(p: Params, phase: float, n: int = 1, tries: int = 8):
    """States on the section where a run from rest arrives after the paper's transient:
    the last one first, then earlier ones (Newton starts when the motion is not periodic)."""
    periods = max(int(math.ceil(SETTLE_TIME / p.T)), 4 * n)
    t_end = phase + periods * p.T
    t_rec = max(0.0, t_end - (tries - 1) * n * p.T - 0.5 * p.T)
    sol = simulate(p, t_end=t_end, t_record=t_rec, phase=phase)
    if len(sol.poincare) == 0:
        tf, xf, vf, _ = sol.final
        return [(xf, vf)]
    pts = list(zip(sol.poincare.x[::-1].tolist(), sol.poincare.v[::-1].tolist()))
    return pts[::n][:tries]


def _solve_shifted(J, fx, fv):
    """dz with (J - I) dz = -F, by Cramer's rule (None when J - I is singular)."""
    a, b, c, d = J[0] - 1.0, J[1], J[2], J[3] - 1.0
    det = a * d - b * c
    if det != 0.0 and math.isfinite(det):
        return (-fx * d + fv * b) / det, (-fv * a + fx * c) / det
    try:        # products beyond the float range (a strongly unstable orbit): LAPACK scales
        dx, dv = np.linalg.solve(np.array([[a, b], [c, d]]), [-fx, -fv]).tolist()
    except np.linalg.LinAlgError:
        return None
    return dx, dv


def _newton(f, p, x0, v0):
    # 2-vectors as Python floats: numpy's per-call cost on 2 elements exceeds the map's
    x, v = float(x0), float(v0)
    x1, v1, J, info = f(x, v)
    fx, fv = x1 - x, v1 - v
    converged = False
    it = 0
    message = ""
    for it in range(1, NEWTON_MAX + 1):
        scale = 1.0 + max(abs(x), abs(v))
        fn = max(abs(fx), abs(fv))
        if fn <= NEWTON_TOL * scale:
            converged = True
            break
        dz = _solve_shifted(J, fx, fv)
        if dz is None:
            message = "Newton stopped: the map's Jacobian has a multiplier 1 here"
            break
        dx, dv = dz
        if not (math.isfinite(dx) and math.isfinite(dv)):
            message = "Newton stopped: non-finite step (grazing impact?)"
            break
        lam = 1.0
        for _ in range(12):
            xt, vt = max(x + lam * dx, p.g), v + lam * dv
            x1t, v1t, Jt, infot = f(xt, vt)
            fxt, fvt = x1t - xt, v1t - vt
            if max(abs(fxt), abs(fvt)) < fn or lam < 1e-3:
                break
            lam *= 0.5
        x, v, J, info, fx, fv = xt, vt, Jt, infot, fxt, fvt
    else:
        message = f"Newton did not converge in {NEWTON_MAX} steps"
    return x, v, J, info, (fx, fv), converged, it, message


def multipliers_of(J) -> np.ndarray:
    """Eigenvalues of the 2 x 2 matrix J (flat or 2 x 2), largest modulus first."""
    a, b, c, d = (float(e) for e in np.ravel(J))
    if not all(math.isfinite(e) for e in (a, b, c, d)):
        return np.array([complex(np.nan), complex(np.nan)])
    if max(abs(a), abs(b), abs(c), abs(d)) > 1e150:
        # squares would overflow: LAPACK balances the matrix first
        mu = np.linalg.eigvals(np.array([[a, b], [c, d]])).astype(complex)
        return mu[np.argsort(-np.abs(mu), kind="stable")]
    # lambda = (a + d) / 2 +- sqrt(((a - d) / 2)^2 + b c): no cancellation in the
    # discriminant from trace^2 / 4 - det; the smaller root from det / the larger
    h, e = 0.5 * (a + d), 0.5 * (a - d)
    disc = e * e + b * c        # a product, not **: huge entries give inf, not OverflowError
    if disc < 0.0:
        w = math.sqrt(-disc)
        return np.array([complex(h, w), complex(h, -w)])
    big = h + math.copysign(math.sqrt(disc), h)
    small = (a * d - b * c) / big if big != 0.0 else 0.0
    return np.array([complex(big), complex(small)])


def orbit_label(m, n, sticks, chatter):
    if chatter:
        return f"complete chattering (∞-impact period-{n})"
    if m == 0:
        return f"no impact (period-{n})"
    base = f"{m}-impact period-{n}"
    return base + " with sticking" if sticks else base


def _minimal_period(f, z, n, tol):
    for d in range(1, n):
        if n % d == 0:
            xd, vd, _, _ = MapEval(f.p, d, f.t0)(*z)
            if max(abs(xd - z[0]), abs(vd - z[1])) <= tol:
                return d
    return n


def periodic_orbit(p: Params, n: int = 1, x0: float | None = None, v0: float | None = None,
                   phase: float = 0.0) -> PeriodicOrbit:
    """A periodic orbit of the n-period stroboscopic map, with its Floquet multipliers.

    Newton's method on F(z) = P^n(z) - z, z = (x, v) on the section t = phase (mod T),
    with the exact Jacobian DP^n = Phi(s_last) S_m ... S_1 Phi(s_0) (flow Jacobians Phi
    and saltation matrices S, :mod:`impactlib.tangent`; Müller 1995; Leine & Nijmeijer
    2004, ch. 7).  A step that does not reduce ``|F|`` is halved (up to 12 times).  Unstable
    orbits are fixed points of P^n like stable ones, so Newton finds them from a start
    close enough.  det DP^n = r^(2 m) exp(-2 c n T / m_mass) for m impacts.

    Parameters
    ----------
    p : Params
    n : int
        Periods of the orbit (>= 1).
    x0, v0 : float, optional
        Start on the section; by default where a run from rest arrives after the paper's
        transient (250 time units), i.e. on the attractor the explorer shows.
    phase : float
        Section time in [0, T].

    Returns
    -------
    PeriodicOrbit
        Never raises for non-convergence: ``converged`` False and ``message`` say why.
        An orbit that sticks has the Jacobian 0 (the release state does not depend on
        the start), so its multipliers are both 0; ``sticks`` and ``message`` say so.
    """
    check_start(p, None, n, x0, v0, phase)
    n = int(n)
    phase = float(phase)
    f = MapEval(p, n, phase)
    if x0 is None or v0 is None:
        starts = settle_starts(p, phase, n)
        if x0 is not None:
            starts = [(float(x0), vs) for _, vs in starts]
        if v0 is not None:
            starts = [(xs, float(v0)) for xs, _ in starts]
    else:
        starts = [(float(x0), float(v0))]
    for x_start, v_start in starts:
        x, v, J, info, F, converged, it, message = _newton(f, p, x_start, v_start)
        if converged:
            break
    z = (x, v)
    residual = max(abs(F[0]), abs(F[1]))
    status, m, sticks, vmin, n_rec, n_tail = info
    imp_t, imp_v = f.impacts(n_rec)
    # a chatter summed to its accumulation point: infinitely many impacts in the cycle
    chatter = n_tail > 0
    d = _minimal_period(f, z, n, 1e-8 * (1.0 + max(abs(x), abs(v)))) if converged else n
    if sticks:
        mu = np.zeros(2, dtype=complex)
        J = np.zeros((2, 2))
        note = "the orbit sticks to the wall, so its map is locally constant: multipliers 0"
        message = f"{message}; {note}" if message else note
    else:
        mu = multipliers_of(J)
        J = np.array(J).reshape(2, 2)
    stable = bool(abs(mu[0]) < 1.0 and abs(mu[1]) < 1.0)
    label = orbit_label(m, n, sticks, chatter)
    if d < n:
        label += f" (repeats after {d} period{'s' if d > 1 else ''})"
    if converged and not message:
        message = "converged"
    # between impacts the exact motion never passes the wall; an impact at (or below)
    # zero speed is a grazing, where the orbit sits on the border of admissibility
    admissible = bool(converged and (m == 0 or sticks or np.all(imp_v < 0.0)))
    return PeriodicOrbit(params=p, x=x, v=v, n=n, phase=phase,
                         impacts=math.inf if chatter else m, label=label, multipliers=mu,
                         stable=stable, admissible=admissible, converged=converged,
                         residual=residual, sticks=bool(sticks), iterations=it,
                         message=message, impact_times=imp_t, impact_velocities=imp_v,
                         jacobian=J)

