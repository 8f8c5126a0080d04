"""An independent prototype of the exact method, for the speed comparison in bench_speed.py.

A plain Numba kernel written from the equations, sharing no code with impactlib: the
closed form of the underdamped flight (Eq. (1); one exp, two sin/cos pairs per
evaluation), a safe step to the first root of the cubic lower bound
f + v tau + a tau^2 / 2 - M3 tau^3 / 6 (M3 = amplitude of the homogeneous part times
w0^3 plus FA omega^3; its root by false position), Newton once a crossing is close, the impact
law v -> -r v, and sticking after a rebound under 1e-12 until cos(omega t) - k g turns
positive.  Underdamped, non-resonant parameters only (the paper's omega diagram); it is
a yardstick, not a solver.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

EPS = 2.220446049250313e-16


@njit(cache=True)
def _lower(f, v, a, m3, tau):
    return f + tau * (v + tau * (0.5 * a - tau * m3 / 6.0))


@njit(cache=True)
def _safe_step(f, v, a, m3, hmax):
    """Largest tau <= hmax with the cubic lower bound positive on (0, tau)."""
    disc = a * a + 2.0 * m3 * v
    lo, hi = 0.0, hmax
    if disc >= 0.0:
        sd = math.sqrt(disc)
        tm = (a - sd) / m3           # local minimum of the cubic
        tp = (a + sd) / m3           # local maximum
        if 0.0 < tm < hmax and _lower(f, v, a, m3, tm) <= 0.0:
            hi = tm
        elif _lower(f, v, a, m3, hmax) > 0.0:
            return hmax
        else:
            lo = max(0.0, tp)
    elif _lower(f, v, a, m3, hmax) > 0.0:
        return hmax
    # Illinois false position on the bracket (p(lo) > 0 >= p(hi)), to 1e-4 relative:
    # the step only has to stay on the safe side
    plo = _lower(f, v, a, m3, lo)
    phi = _lower(f, v, a, m3, hi)
    side = 0
    for _ in range(30):
        if hi - lo <= 1e-4 * hi:
            break
        mid = (lo * -phi + hi * plo) / (plo - phi)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        pm = _lower(f, v, a, m3, mid)
        if pm > 0.0:
            lo, plo = mid, pm
            if side == 1:
                phi *= 0.5
            side = 1
        else:
            hi, phi = mid, pm
            if side == -1:
                plo *= 0.5
            side = -1
    return lo


@njit(cache=True)
def _state(t0, s, A, B, alpha, beta, P, Q, om, m, c, k):
    e = math.exp(-alpha * s)
    cb = math.cos(beta * s)
    sb = math.sin(beta * s)
    cw = math.cos(om * (t0 + s))
    sw = math.sin(om * (t0 + s))
    x = e * (A * cb + B * sb) + P * cw + Q * sw
    v = e * ((beta * B - alpha * A) * cb - (alpha * B + beta * A) * sb) + om * (Q * cw - P * sw)
    a = (cw - 2.0 * c * v - k * x) / m
    return x, v, a


@njit(cache=True)
def prototype_run(m, c, k, g, r, om, t_end, t_record, out_t, out_v):
    """Impacts in [t_record, t_end] from rest at max(0, g), t = 0.  Returns (n_recorded,
    n_impacts, evaluations)."""
    alpha = c / m
    w0sq = k / m
    beta = math.sqrt(w0sq - alpha * alpha)
    det = k - m * om * om
    d = det * det + (2.0 * c * om) ** 2
    P = det / d
    Q = 2.0 * c * om / d
    fa = math.sqrt(P * P + Q * Q)
    hmax = math.pi / om
    t = 0.0
    x = max(0.0, g)
    v = 0.0
    n_rec = 0
    n_imp = 0
    evals = 0
    while t < t_end:
        if x <= g and v <= 0.0:
            # stuck: wait for the net force cos(om t) - k g to turn positive
            kg = k * g
            if kg >= 1.0:
                return n_rec, n_imp, evals
            if math.cos(om * t) - kg <= 0.0:
                th = 2.0 * math.pi - math.acos(max(-1.0, kg))
                n = math.floor((om * t - th) / (2.0 * math.pi))
                tr = (th + 2.0 * math.pi * n) / om
                while tr <= t:
                    n += 1
                    tr = (th + 2.0 * math.pi * n) / om
                t = tr
            x, v = g, 0.0
        cw = math.cos(om * t)
        sw = math.sin(om * t)
        A = x - (P * cw + Q * sw)
        B = (v - om * (Q * cw - P * sw) + alpha * A) / beta
        m3 = math.sqrt(A * A + B * B) * w0sq * math.sqrt(w0sq) + fa * om ** 3
        s = 0.0
        f = x - g
        vv = v
        aa = (cw - 2.0 * c * v - k * x) / m
        hit = False
        while True:
            h = min(hmax, t_end - t - s)
            if h <= 0.0:
                break
            tau = _safe_step(max(f, 0.0), vv, aa, m3, h)
            if vv < 0.0 and tau < 1e-3 * hmax:
                # a crossing close ahead: Newton on the closed form
                for _ in range(20):
                    ds = -f / vv
                    s += ds
                    xx, vv, aa = _state(t, s, A, B, alpha, beta, P, Q, om, m, c, k)
                    evals += 1
                    f = xx - g
                    if abs(ds) <= 4.0 * EPS * (t + s):
                        break
                hit = True
                break
            if tau >= h and t + s + h >= t_end:
                s += h
                break
            s += tau
            xx, vv, aa = _state(t, s, A, B, alpha, beta, P, Q, om, m, c, k)
            evals += 1
            f = xx - g
        t += s
        if not hit:
            break
        n_imp += 1
        if t >= t_record:
            if n_rec < out_t.shape[0]:
                out_t[n_rec] = t
                out_v[n_rec] = vv
            n_rec += 1
        x = g
        v = -r * vv
        if v < 1e-12:
            v = 0.0
    return n_rec, n_imp, evals


def prototype(p, t_end=500.0, t_record=250.0, cap=4096):
    """One run of the prototype: (impact times, velocities, all impacts, evaluations)."""
    out_t = np.empty(cap)
    out_v = np.empty(cap)
    n_rec, n_imp, evals = prototype_run(p.m, p.c, p.k, p.g, p.r, p.omega, t_end, t_record,
                                        out_t, out_v)
    n = min(n_rec, cap)
    return out_t[:n].copy(), out_v[:n].copy(), n_imp, evals
