"""The defining system of one boundary curve (:func:`impactlib.boundary`) and its
corrector: unknowns y = (t_1..t_m, u_1..u_m, [s], a, b) (the orbit's impact times and
velocities, a touching flight's touch time, both parameters), the multi-segment
equations of :mod:`impactlib.continuation` plus the event's defining condition, Newton
on them with the pseudo-arclength row, the tangent, and what is watched along the curve
(multipliers, the orbit's lowest points, the touch's curvature)."""
from __future__ import annotations

import math

import numpy as np

from ..kernels.flight import G, R, flight_state, start_segment, system_constants
from ..kernels.grazing import CLEARANCE_SAMPLES, ENDS_MARGIN, lowest_in_flight
from ..kernels.tangent import flow_jacobian, saltation
from ..model import FIELDS, MAGNITUDE_MAX, MAGNITUDE_MIN, PARAM_NAMES, Params
from .continuation import (segments_clearance, segments_monodromy, segments_residual,
                           segments_section)

NEWTON_TOL = 1e-11
NEWTON_MAX = 8


def in_range(name, value) -> bool:
    """value lies in the valid range of parameter ``name`` (as Params checks it)."""
    f = FIELDS[name]
    if not (math.isfinite(value) and abs(value) <= MAGNITUDE_MAX):
        return False
    if f.lo is not None and (value < f.lo or (f.lo_open and value == f.lo)):
        return False
    if f.hi is not None and value > f.hi:
        return False
    return not (name in ("m", "omega") and value < MAGNITUDE_MIN)


class CurveSystem:
    """The defining system of one curve: unknowns y = (t_1..t_m, u_1..u_m, [s], a, b)."""

    def __init__(self, p: Params, names, n, m, phase, kind, touch):
        self.p, self.names, self.n, self.m, self.phase = p, names, n, m, phase
        self.kind, self.touch = kind, touch
        self.q = 1 if touch is not None and touch[0] == "flight" else 0
        self.nz = 2 * m + self.q + 2
        self.F = np.empty(2 * m)
        self.DF = np.empty((2 * m, 2 * m))
        self._cache = {}
        self.base = tuple(getattr(p, n) for n in PARAM_NAMES)
        self.last_jacobian = None

    def params(self, lam) -> Params:
        return self.p.replace(**{self.names[0]: float(lam[0]), self.names[1]: float(lam[1])})

    def sp(self, lam):
        key = (float(lam[0]), float(lam[1]))
        got = self._cache.get(key)
        if got is None:
            # the bounds of Params' validation, without building one at every evaluation
            for name, value in zip(self.names, key):
                if not in_range(name, value):
                    raise ValueError(f"{name}={value!r} is outside its valid range")
            q = dict(zip(PARAM_NAMES, self.base))
            q.update(zip(self.names, key))
            got = (system_constants(q["m"], q["c"], q["k"], q["g"], q["r"], q["omega"]),
                   self.n * 2.0 * math.pi / q["omega"])
            if len(self._cache) > 16:
                self._cache.clear()
            self._cache[key] = got
        return got

    def clip(self, y):
        """y with both parameters moved onto their closed edges if beyond them (projected
        Newton: a solution inside the range is found from a step that overshoots)."""
        for k, name in enumerate(self.names):
            i = self.nz - 2 + k
            f = FIELDS[name]
            if f.lo is not None and not f.lo_open and y[i] < f.lo:
                y[i] = f.lo
            if f.hi is not None and y[i] > f.hi:
                y[i] = f.hi
        return y

    def split(self, y):
        m = self.m
        return y[:m], y[m:2 * m], y[2 * m:2 * m + self.q]

    def next_time(self, ts, total, j):
        return ts[j + 1] if j + 1 < self.m else ts[0] + total

    def touch_state(self, sp, ts, us, s):
        """(x, v, a) of the touching flight at its unknown time s."""
        j = self.touch[1]
        seg = start_segment(sp, ts[j], sp[G], -sp[R] * us[j])
        x, v, a, _, _, _ = flight_state(sp, seg, s)
        return x, v, a

    def conditions(self, sp, total, ts, us, s):
        if self.touch is None:
            a11, a12, a21, a22, P, det = segments_monodromy(sp, ts, us, total)
            sgn = -1.0 if self.m % 2 else 1.0
            tr = a11 + a22
            phi = P * (1.0 + det) + (tr if self.kind == "period-doubling" else -tr)
            return [sgn * phi]
        if self.touch[0] == "impact":
            return [us[self.touch[1]]]
        x, v, _ = self.touch_state(sp, ts, us, s[0])
        return [x - sp[G], v]

    def residual(self, y):
        sp, total = self.sp(y[-2:])
        ts, us, s = self.split(y)
        segments_residual(sp, ts, us, total, self.F, self.DF)
        return np.concatenate([self.F, self.conditions(sp, total, ts, us, s)])

    def condition_columns(self) -> range | tuple:
        """The (t, u) unknowns the defining condition depends on: all of them for a
        multiplier condition, u_j for an impact at zero speed, t_j and u_j (the start of
        the touching flight) for a flight touching the wall."""
        m = self.m
        if self.touch is None:
            return range(2 * m)
        j = self.touch[1]
        return (m + j,) if self.touch[0] == "impact" else (j, m + j)

    def jacobian(self, y):
        """(H, DH): exact in (t, u) for the multi-segment rows, central differences for
        the condition rows and for the extra and parameter columns.  A (t, u) column
        needs the conditions only, at the unknowns they depend on (the others are 0)."""
        m2 = 2 * self.m
        H = self.residual(y)
        J = np.zeros((self.nz - 1, self.nz))
        J[:m2, :m2] = self.DF
        sp, total = self.sp(y[-2:])
        for i in self.condition_columns():
            h = 1e-7 * (1.0 + abs(y[i]))
            yp = y.copy()
            yp[i] += h
            ym = y.copy()
            ym[i] -= h
            cp = self.conditions(sp, total, *self.split(yp))
            cm = self.conditions(sp, total, *self.split(ym))
            J[m2:, i] = (np.asarray(cp) - np.asarray(cm)) / (yp[i] - ym[i])
        for i in range(m2, self.nz):
            param = i >= self.nz - 2
            h = (1e-6 * max(1.0, abs(y[i]))) if param else 1e-7 * (1.0 + abs(y[i]))
            yp = y.copy()
            yp[i] += h
            ym = y.copy()
            ym[i] -= h
            try:
                hp = self.residual(yp)
            except ValueError:       # at the edge of a parameter's valid range: one-sided
                hp, yp = H, y
            try:
                hm = self.residual(ym)
            except ValueError:
                hm, ym = H, y
            J[:, i] = (hp - hm) / (yp[i] - ym[i])
        return H, J

    def converged(self, H, J, y):
        m2 = 2 * self.m
        scale = 1.0 + np.max(np.abs(y))
        grad = max(1.0, float(np.max(np.abs(J[m2:]))))
        return (np.max(np.abs(H[:m2])) <= NEWTON_TOL * scale
                and np.max(np.abs(H[m2:])) <= NEWTON_TOL * scale * grad)

    def correct(self, y_pred, row, target):
        """Newton on [H(y); row . y - target]; (y, iterations), y None on failure.  On
        success ``last_jacobian`` holds the Jacobian of the last step (taken at most
        1e-12 (relative) before y, or where Newton's final steps no longer move it)."""
        self.last_jacobian = None
        y = y_pred.copy()
        A = np.empty((self.nz, self.nz))
        b = np.empty(self.nz)
        J = None
        for it in range(1, NEWTON_MAX + 1):
            try:
                H, J = self.jacobian(y)
            except ValueError:
                return None, it
            A[:-1] = J
            A[-1] = row
            b[:-1] = H
            b[-1] = row @ y - target
            try:
                dy = np.linalg.solve(A, -b)
            except np.linalg.LinAlgError:
                return None, it
            if not np.all(np.isfinite(dy)):
                return None, it
            y = self.clip(y + dy)
            if np.max(np.abs(dy)) <= 1e-12 * (1.0 + np.max(np.abs(y))):
                try:
                    H = self.residual(y)
                except ValueError:
                    return None, it
                if self.converged(H, J, y):
                    self.last_jacobian = J
                    return y, it
        try:
            H = self.residual(y)
        except ValueError:
            return None, NEWTON_MAX
        if J is not None and self.converged(H, J, y):
            self.last_jacobian = J
            return y, NEWTON_MAX
        return None, NEWTON_MAX

    def tangent(self, y, t_prev=None, J=None):
        """The unit tangent at y (the null vector of the Jacobian, ``J`` if given),
        oriented along ``t_prev``."""
        if J is None:
            _, J = self.jacobian(y)
        qm, _ = np.linalg.qr(J.T, mode="complete")
        t = qm[:, -1]
        if t_prev is not None and float(t @ t_prev) < 0.0:
            t = -t
        return t / np.linalg.norm(t)

    def monodromy(self, sp, ts, us, total):
        """M of the orbit, the saltation of a zero-speed (touching) impact left out."""
        skip = self.touch[1] if self.touch is not None and self.touch[0] == "impact" else -1
        M = np.eye(2)
        for j in range(self.m):
            jn = j + 1 if j + 1 < self.m else 0
            t1 = self.next_time(ts, total, j)
            M = np.array(flow_jacobian(sp, t1 - ts[j])).reshape(2, 2) @ M
            if jn != skip:
                M = np.array(saltation(sp, t1, us[jn])).reshape(2, 2) @ M
        return M

    def wall(self, sp, ts, us, total, s):
        """Lowest of: minus each impact speed, each flight's interior clearance; the
        touch itself left out on a grazing curve."""
        if self.touch is None:
            return min(-float(np.max(us)),
                       segments_clearance(sp, ts, us, total, CLEARANCE_SAMPLES))
        kind, jt = self.touch
        out = math.inf
        for j in range(self.m):
            if not (kind == "impact" and j == jt):
                out = min(out, -float(us[j]))
            t1 = self.next_time(ts, total, j)
            seg = start_segment(sp, ts[j], sp[G], -sp[R] * us[j])
            skip = s[0] if (kind == "flight" and j == jt) else math.nan
            out = min(out, lowest_in_flight(sp, seg, t1 - ts[j], skip, CLEARANCE_SAMPLES)[0])
        return out

    def describe(self, y):
        """(x, v, multipliers, touch time, tests) at a point of the curve."""
        sp, total = self.sp(y[-2:])
        ts, us, s = self.split(y)
        x, v = segments_section(sp, ts, us, total, self.phase)
        M = self.monodromy(sp, ts, us, total)
        if np.all(np.isfinite(M)):
            mu = np.linalg.eigvals(M).astype(complex)
            mu = mu[np.argsort(-np.abs(mu), kind="stable")]
        else:
            mu = np.array([complex(math.inf), complex(0.0)])
        tests = {"wall": self.wall(sp, ts, us, total, s)}
        touch_t = math.nan
        if self.touch is not None:
            tr, det = float(np.trace(M)), float(np.linalg.det(M))
            tests["period-doubling"] = 1.0 + tr + det
            tests["saddle-node"] = 1.0 - tr + det
            j = self.touch[1]
            if self.touch[0] == "impact":
                touch_t = float(ts[j])
                # arriving with zero speed from above: x'' >= 0 there
                seg = start_segment(sp, ts[j], sp[G], 0.0)
                tests["curvature"] = flight_state(sp, seg, 0.0)[2]
            else:
                touch_t = float(ts[j] + s[0])
                tests["curvature"] = self.touch_state(sp, ts, us, s[0])[2]
                dur = self.next_time(ts, total, j) - ts[j]
                # the touch merging with an impact ends the flight's grazing
                tests["touch inside"] = min(s[0], dur - s[0]) - ENDS_MARGIN * dur
        return x, v, mu, touch_t, tests
