"""Step-by-step integrators of the flight, for comparison with the closed form.

``rk4``: classical fixed-step Runge-Kutta (the paper's method); an impact is detected
when a step ends behind the wall and located on the step's cubic Hermite interpolant.
``rk45``: adaptive Dormand-Prince 5(4) with its quartic dense output (coefficients as in
scipy.integrate.RK45, Shampine 1986); an impact is detected at the ends of accepted steps
and located on the dense output.  Both check for impacts only at step ends, as such
integrators do: a dip below the wall inside one step is missed, by design of the method.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit
from .events import EPS, IMPACT, NO_IMPACT, STEP_LIMIT
from .flight import C_, G, K, M, OM

_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0],
    [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
])
_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
_E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
_P = np.array([
    [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0.0, 0.0, 0.0, 0.0],
    [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])


@jit
def accel(sp, t, x, v):
    """x'' from Eq. (1) in flight."""
    return (math.cos(sp[OM] * t) - 2.0 * sp[C_] * v - sp[K] * x) / sp[M]


@jit
def _hermite(x0, v0, x1, v1, h, th):
    th2 = th * th
    th3 = th2 * th
    x = ((2 * th3 - 3 * th2 + 1) * x0 + (th3 - 2 * th2 + th) * h * v0
         + (-2 * th3 + 3 * th2) * x1 + (th3 - th2) * h * v1)
    v = ((6 * th2 - 6 * th) * x0 / h + (3 * th2 - 4 * th + 1) * v0
         + (-6 * th2 + 6 * th) * x1 / h + (3 * th2 - 2 * th) * v1)
    return x, v


@jit
def _sample_hermite(t, h, x0, v0, x1, v1, t_hi, ts, xs, vs, i):
    while i < ts.shape[0] and ts[i] <= t_hi:
        xs[i], vs[i] = _hermite(x0, v0, x1, v1, h, (ts[i] - t) / h)
        i += 1
    return i


@jit
def advance_rk4(sp, t, x, v, t_end, dt, pc_t, pc_x, pc_v, ip, d_t, d_x, d_v, idn, max_steps):
    """Fixed-step RK4 from (t, x, v) to the next impact or t_end.

    Returns (kind, t, x, v, nsteps, ip, idn): at an impact, the state just before it.
    """
    g = sp[G]
    n = 0
    while True:
        if t >= t_end:
            return NO_IMPACT, t, x, v, n, ip, idn
        h = min(dt, t_end - t)
        k1x, k1v = v, accel(sp, t, x, v)
        k2x, k2v = v + 0.5 * h * k1v, accel(sp, t + 0.5 * h, x + 0.5 * h * k1x, v + 0.5 * h * k1v)
        k3x, k3v = v + 0.5 * h * k2v, accel(sp, t + 0.5 * h, x + 0.5 * h * k2x, v + 0.5 * h * k2v)
        k4x, k4v = v + h * k3v, accel(sp, t + h, x + h * k3x, v + h * k3v)
        x1 = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x)
        v1 = v + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
        n += 1
        if x1 < g:
            lo, hi = 0.0, 1.0
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                xm, vm = _hermite(x, v, x1, v1, h, mid)
                if xm > g:
                    lo = mid
                else:
                    hi = mid
            th = 0.5 * (lo + hi)
            xh, vh = _hermite(x, v, x1, v1, h, th)
            th_t = t + th * h
            ip = _sample_hermite(t, h, x, v, x1, v1, th_t, pc_t, pc_x, pc_v, ip)
            idn = _sample_hermite(t, h, x, v, x1, v1, th_t, d_t, d_x, d_v, idn)
            return IMPACT, th_t, g, min(vh, 0.0), n, ip, idn
        ip = _sample_hermite(t, h, x, v, x1, v1, t + h, pc_t, pc_x, pc_v, ip)
        idn = _sample_hermite(t, h, x, v, x1, v1, t + h, d_t, d_x, d_v, idn)
        t, x, v = t + h, x1, v1
        if n >= max_steps:
            return STEP_LIMIT, t, x, v, n, ip, idn


@jit
def _dop_eval(x, v, h, qx, qv, th):
    # y(t + th h) = y + h * sum_j Q_j th^(j+1); derivative = sum_j (j+1) Q_j th^j
    px = 0.0
    pv = 0.0
    dx = 0.0
    p = th
    for j in range(4):
        px += qx[j] * p
        pv += qv[j] * p
        p *= th
    pj = 1.0
    for j in range(4):
        dx += (j + 1) * qx[j] * pj
        pj *= th
    return x + h * px, v + h * pv, dx


@jit
def _sample_dop(t, h, x, v, qx, qv, t_hi, ts, xs, vs, i):
    while i < ts.shape[0] and ts[i] <= t_hi:
        xs[i], vs[i], _ = _dop_eval(x, v, h, qx, qv, (ts[i] - t) / h)
        i += 1
    return i


@jit
def advance_rk45(sp, t, x, v, h, t_end, rtol, atol, pc_t, pc_x, pc_v, ip, d_t, d_x, d_v, idn,
                 max_steps):
    """Adaptive Dormand-Prince 5(4) from (t, x, v) to the next impact or t_end.

    Returns (kind, t, x, v, h_next, nsteps, ip, idn).
    """
    g = sp[G]
    kx = np.empty(7)
    kv = np.empty(7)
    qx = np.empty(4)
    qv = np.empty(4)
    kx[0] = v
    kv[0] = accel(sp, t, x, v)
    n = 0
    while True:
        if t >= t_end:
            return NO_IMPACT, t, x, v, h, n, ip, idn
        h = min(h, t_end - t)
        hmin = 16.0 * EPS * max(abs(t), 1.0)
        if h < hmin:
            return STEP_LIMIT, t, x, v, h, n, ip, idn
        for s in range(1, 6):
            dx = 0.0
            dv = 0.0
            for j in range(s):
                dx += _A[s, j] * kx[j]
                dv += _A[s, j] * kv[j]
            xs = x + h * dx
            vs = v + h * dv
            kx[s] = vs
            kv[s] = accel(sp, t + _C[s] * h, xs, vs)
        dx = 0.0
        dv = 0.0
        for j in range(6):
            dx += _B[j] * kx[j]
            dv += _B[j] * kv[j]
        x1 = x + h * dx
        v1 = v + h * dv
        kx[6] = v1
        kv[6] = accel(sp, t + h, x1, v1)
        ex = 0.0
        ev = 0.0
        for j in range(7):
            ex += _E[j] * kx[j]
            ev += _E[j] * kv[j]
        ex *= h / (atol + rtol * max(abs(x), abs(x1)))
        ev *= h / (atol + rtol * max(abs(v), abs(v1)))
        err = math.sqrt(0.5 * (ex * ex + ev * ev))
        n += 1
        if n >= max_steps:
            return STEP_LIMIT, t, x, v, h, n, ip, idn
        if err < 1.0:
            for c in range(4):
                sx = 0.0
                sv = 0.0
                for j in range(7):
                    sx += kx[j] * _P[j, c]
                    sv += kv[j] * _P[j, c]
                qx[c] = sx
                qv[c] = sv
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** -0.2)
            if x1 < g:
                lo, hi = 0.0, 1.0
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    xm, vm, dm = _dop_eval(x, v, h, qx, qv, mid)
                    if xm > g:
                        lo = mid
                    else:
                        hi = mid
                th = 0.5 * (lo + hi)
                xh, vh, dxh = _dop_eval(x, v, h, qx, qv, th)
                th_t = t + th * h
                ip = _sample_dop(t, h, x, v, qx, qv, th_t, pc_t, pc_x, pc_v, ip)
                idn = _sample_dop(t, h, x, v, qx, qv, th_t, d_t, d_x, d_v, idn)
                return IMPACT, th_t, g, min(dxh, 0.0), h * fac, n, ip, idn
            ip = _sample_dop(t, h, x, v, qx, qv, t + h, pc_t, pc_x, pc_v, ip)
            idn = _sample_dop(t, h, x, v, qx, qv, t + h, d_t, d_x, d_v, idn)
            t, x, v = t + h, x1, v1
            kx[0] = kx[6]
            kv[0] = kv[6]
            h *= fac
        else:
            h *= max(0.2, 0.9 * err ** -0.2)
