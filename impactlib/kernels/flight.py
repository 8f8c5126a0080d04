"""Closed-form motion between impacts.

Away from the wall Eq. (1) is linear, so x(t) = h(t) + x_p(t): a homogeneous part and a
particular (steady forced) part.  Writing alpha = c/m, w0^2 = k/m and q = w0^2 - alpha^2,

    h(s) = h0 e^{-alpha s} (C + alpha S) + hv0 e^{-alpha s} S,
    C = cos(sqrt(q) s), S = sin(sqrt(q) s)/sqrt(q)            (q > 0, underdamped)
    C = 1,              S = s                                   (q = 0, critical)
    C = cosh(b s),      S = sinh(b s)/b,  b = sqrt(-q)          (q < 0, overdamped)

sin(z)/sqrt(q) and sinh(z)/b stay accurate as q -> 0, so near-critical damping has no
cancellation; for large b s the overdamped pair is evaluated from its two exponentials
lam1 = -w0^2/(alpha + b) (the slow root, cancellation-free) and lam2 = -(alpha + b).

The particular part is P cos(wt) + Q sin(wt) with P = (k - m w^2)/D, Q = 2 c w / D,
D = (k - m w^2)^2 + (2 c w)^2; at exact resonance (c = 0, m w^2 = k) it is
t sin(wt) / (2 m w).  Each flight segment stores the forcing relative to its own start
(angle addition), so its phase and, at resonance, its secular term stay small.

System constants live in a float64 array ``sp`` and a segment in ``seg``; the index
names below are their layout.  Kernels only read them by index, so either may also be a
tuple of that layout: the engine passes tuples (:func:`make_segment`), which Numba
passes by value, where an array argument costs atomic reference counting on every call
of a kernel that calls another.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit

# sp layout
(M, C_, K, G, R, OM, ALPHA, Q_, SQ, W0SQ, LAM1, LAM2, PP, QQ, RES, FA, EV, EKX, EGROW, INV_M,
 HRATE, NSP) = range(22)
# seg layout
T0, CPH, SPH, FC, FS, H0, HV0, X0, V0, NSEG = range(10)

EPS = 2.220446049250313e-16
RESONANCE_RTOL = 16 * EPS


@jit
def fill_constants(sp, m, c, k, g, r, omega):
    """Write the constants of Eq. (1) used by every kernel into the row ``sp`` (length NSP)."""
    sp[M], sp[C_], sp[K], sp[G], sp[R], sp[OM] = m, c, k, g, r, omega
    alpha = c / m
    w0sq = k / m
    q = (k * m - c * c) / (m * m)
    b = math.sqrt(abs(q))
    sp[ALPHA], sp[W0SQ], sp[Q_], sp[SQ] = alpha, w0sq, q, b
    if q < 0.0:
        sp[LAM1] = -w0sq / (alpha + b)
        sp[LAM2] = -(alpha + b)
    else:
        sp[LAM1] = 0.0
        sp[LAM2] = 0.0
    # derivative_bounds' factors: |h''| <= HRATE rh; |v| <= EV sqrt(E), k |x| <= EKX sqrt(E)
    # and sqrt(E) grows by at most EGROW per unit time (motion_bounds)
    sp[HRATE] = 2.0 * alpha + math.sqrt(w0sq)
    sp[EV], sp[EKX] = math.sqrt(2.0 / m), math.sqrt(2.0 * k)
    sp[EGROW], sp[INV_M] = 1.0 / math.sqrt(2.0 * m), 1.0 / m
    detune = k - m * omega * omega
    res = c == 0.0 and abs(detune) <= RESONANCE_RTOL * max(k, m * omega * omega)
    if res:
        sp[RES], sp[PP], sp[QQ] = 1.0, 0.0, 0.0
        sp[FA] = 1.0 / (2.0 * m * omega)
    else:
        d = detune * detune + (2.0 * c * omega) ** 2
        sp[RES], sp[PP], sp[QQ] = 0.0, detune / d, 2.0 * c * omega / d
        sp[FA] = math.hypot(sp[PP], sp[QQ])


@jit
def system_constants(m, c, k, g, r, omega):
    """The constants ``sp`` of Eq. (1) used by every kernel, for one set of parameters."""
    sp = np.empty(NSP)
    fill_constants(sp, m, c, k, g, r, omega)
    return sp


@jit
def system_constants_rows(m, c, k, g, r, omega):
    """system_constants for arrays of parameters: one row of ``sp`` per entry."""
    n = m.shape[0]
    sp = np.empty((n, NSP))
    for i in range(n):
        fill_constants(sp[i], m[i], c[i], k[i], g[i], r[i], omega[i])
    return sp


@jit
def fastest_rate(sp):
    """Fastest rate of the linear flow and the forcing, 1/s (as impactlib.model.fastest_rate)."""
    a = sp[C_] / sp[M]
    w0sq = sp[K] / sp[M]
    lam = a + math.sqrt(abs(a * a - w0sq)) if a * a > w0sq else math.sqrt(w0sq)
    return max(max(lam, sp[OM]), sp[C_] / sp[M])


@jit
def start_segment(sp, t0, x0, v0):
    """Segment of free flight from state (x0, v0) at time t0, as a new array."""
    vals = make_segment(sp, t0, x0, v0)
    seg = np.empty(NSEG)
    for i in range(NSEG):
        seg[i] = vals[i]
    return seg


@jit
def make_segment(sp, t0, x0, v0):
    """Segment of free flight from state (x0, v0) at time t0, as a tuple (the layout of
    ``seg``): no allocation, and no reference counting where it is passed on."""
    om = sp[OM]
    ph = om * t0
    cph = math.cos(ph)
    sph = math.sin(ph)
    if sp[RES] != 0.0:
        # x_p(s) = s sin(om s + ph) / (2 m om) = s (A cos om s + B sin om s)
        fc = sph * sp[FA]
        fs = cph * sp[FA]
        xp0 = 0.0
        vp0 = fc
    else:
        fc = sp[PP] * cph + sp[QQ] * sph
        fs = sp[QQ] * cph - sp[PP] * sph
        xp0 = fc
        vp0 = om * fs
    return (t0, cph, sph, fc, fs, x0 - xp0, v0 - vp0, x0, v0)


@jit
def flight_state(sp, seg, s):
    """State s time units into a segment.

    Returns
    -------
    x, v, a, j : float
        Displacement and its first three time derivatives at t0 + s.
    rh : float
        sqrt(h'^2 + w0^2 h^2) of the homogeneous part, a bound that never grows (energy).
    xs : float
        Size of the summed terms, for the rounding error of x.
    """
    alpha = sp[ALPHA]
    q = sp[Q_]
    sq = sp[SQ]
    w0sq = sp[W0SQ]
    # e^{-alpha s} C - 1 (eCm1) and e^{-alpha s} S, via half angles and expm1 so that the
    # increment from the segment start stays accurate for small s (short chatter hops)
    if q > 0.0:
        em1 = math.expm1(-alpha * s)
        half = 0.5 * sq * s
        sh = math.sin(half)
        ch = math.cos(half)
        cm1 = -2.0 * sh * sh
        eCm1 = em1 * (1.0 + cm1) + cm1
        eS = (1.0 + em1) * 2.0 * sh * ch / sq
    elif q == 0.0:
        em1 = math.expm1(-alpha * s)
        eCm1 = em1
        eS = (1.0 + em1) * s
    else:
        z = sq * s
        if z < 1.0:
            em1 = math.expm1(-alpha * s)
            shh = math.sinh(0.5 * z)
            chh = math.cosh(0.5 * z)
            cm1 = 2.0 * shh * shh
            eCm1 = em1 * (1.0 + cm1) + cm1
            eS = (1.0 + em1) * 2.0 * shh * chh / sq
        elif z < 20.0:
            ex = math.exp(-alpha * s)
            eCm1 = ex * math.cosh(z) - 1.0
            eS = ex * math.sinh(z) / sq
        else:
            e1 = math.exp(sp[LAM1] * s)
            e2 = math.exp(sp[LAM2] * s)
            eCm1 = 0.5 * (e1 + e2) - 1.0
            eS = 0.5 * (e1 - e2) / sq
    h0 = seg[H0]
    hv0 = seg[HV0]
    dh = h0 * eCm1 + (hv0 + alpha * h0) * eS
    dhd = -w0sq * h0 * eS + hv0 * (eCm1 - alpha * eS)
    h = h0 + dh
    hd = hv0 + dhd
    hdd = -2.0 * alpha * hd - w0sq * h
    hddd = -2.0 * alpha * hdd - w0sq * hd

    om = sp[OM]
    fc = seg[FC]
    fs = seg[FS]
    hw = 0.5 * om * s
    shw = math.sin(hw)
    chw = math.cos(hw)
    cwm1 = -2.0 * shw * shw
    sw = 2.0 * shw * chw
    cw = 1.0 + cwm1
    u = fc * cw + fs * sw
    ud = om * (fs * cw - fc * sw)
    du = fc * cwm1 + fs * sw                  # u(s) - u(0)
    if sp[RES] != 0.0:
        dxp = s * u                           # x_p(0) = 0
        dxpd = du + s * ud                    # x_p'(0) = u(0)
        xpdd = 2.0 * ud - s * om * om * u
        xpddd = -3.0 * om * om * u - s * om * om * ud
    else:
        dxp = du
        dxpd = om * (fs * cwm1 - fc * sw)     # u'(s) - u'(0)
        xpdd = -om * om * u
        xpddd = -om * om * ud
    rh = math.sqrt(hd * hd + w0sq * h * h)
    x = seg[X0] + (dh + dxp)
    v = seg[V0] + (dhd + dxpd)
    return x, v, hdd + xpdd, hddd + xpddd, rh, abs(seg[X0]) + abs(dh) + abs(dxp)


@jit
def derivative_bounds(sp, rh, s_max, x, v, span):
    """Bounds on |x'''| and |x''''| valid from now until s_max into the segment.

    The smaller of two bounds, each valid on its own:

    * split: the homogeneous energy h'^2 + w0^2 h^2 never grows, so |h'| <= rh and
      w0 |h| <= rh; the higher derivatives follow from h'' = -2 alpha h' - w0^2 h.  The
      forcing part has amplitude FA and gains a factor omega per derivative (plus the
      secular term at resonance, bounded with s <= s_max).  Tight far from resonance.
    * energy (:func:`motion_bounds`), from the state (x, v) now over the ``span`` time
      units left until s_max.  It does not see the split, so near resonance, where FA ~
      1/(c omega) and rh are huge and cancel in x, it stays the size of the motion.
    """
    alpha = sp[ALPHA]
    w0sq = sp[W0SQ]
    b2 = rh * sp[HRATE]
    b3 = 2.0 * alpha * b2 + w0sq * rh
    b4 = 2.0 * alpha * b3 + w0sq * b2
    om = sp[OM]
    fa = sp[FA]
    om3 = om * om * om
    if sp[RES] != 0.0:
        f3 = fa * (3.0 * om * om + s_max * om3)
        f4 = fa * (4.0 * om3 + s_max * om3 * om)
    else:
        f3 = fa * om3
        f4 = f3 * om
    e3, e4 = motion_bounds(sp, x, v, span, 4)
    return min(b3 + f3, e3), min(b4 + f4, e4)


@jit
def motion_bounds(sp, x, v, span, order):
    """Bounds on |x^(order - 1)| and |x^(order)| (order >= 2) over the next ``span`` time
    units of flight from the state (x, v), from the mechanical energy
    E = m v^2 / 2 + k x^2 / 2.

    Along Eq. (1), dE/dt = v (m x'' + k x) = v cos(omega t) - 2 c v^2 <= |v|
    <= sqrt(2 E / m), so d sqrt(E)/dt <= 1 / sqrt(2 m) and over the span
    sqrt(E) <= e = sqrt(E(0)) + span / sqrt(2 m).  Then |x'| <= e sqrt(2 / m) and
    k |x| <= e sqrt(2 k); Eq. (1) and its derivatives, m x^(j+2) = (d/dt)^j cos(omega t)
    - 2 c x^(j+1) - k x^(j), give the rest.  No particular or homogeneous part enters.
    """
    c2, k, om, im = 2.0 * sp[C_], sp[K], sp[OM], sp[INV_M]
    e = math.sqrt(0.5 * (sp[M] * v * v + k * x * x)) * (1.0 + 8.0 * EPS) + span * sp[EGROW]
    b_prev = e * sp[EV]
    b = (1.0 + c2 * b_prev + e * sp[EKX]) * im
    fj = 1.0
    for j in range(1, order - 1):
        fj *= om
        b_prev, b = b, (fj + c2 * b + k * b_prev) * im
    return b_prev, b


@jit
def wall_force(sp, t):
    """Net force on a mass resting on the wall (x = g, v = 0): cos(omega t) - k g."""
    return math.cos(sp[OM] * t) - sp[K] * sp[G]


@jit
def release_time(sp, t):
    """First time >= t at which a mass stuck to the wall leaves it: the net force
    cos(omega t) - k g crosses zero upwards.  inf if the force never turns positive."""
    kg = sp[K] * sp[G]
    om = sp[OM]
    if kg >= 1.0:
        return math.inf
    if kg < -1.0:
        return t
    if wall_force(sp, t) > 0.0:
        return t
    # zero crossing upwards at om t = 2 pi n - arccos(kg)
    theta = 2.0 * math.pi - math.acos(kg)
    n = math.floor((om * t - theta) / (2.0 * math.pi))
    tr = (theta + 2.0 * math.pi * n) / om
    while tr < t:
        if t - tr <= 4e-16 * (abs(t) + 1.0 / om):
            return t   # t sits on a crossing, up to rounding
        n += 1.0
        tr = (theta + 2.0 * math.pi * n) / om
    return tr
