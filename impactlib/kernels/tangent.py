"""Tangent dynamics of the impact oscillator: flow Jacobians, saltation matrices, and a
the algebra that carries a 2x2 tangent matrix along a run (the engine,
:mod:`impactlib.engine`, applies it event by event).

Flow Jacobian
-------------
Between impacts Eq. (1) is linear, y' = A y + f(t) with y = (x, v) and
A = [[0, 1], [-w0^2, -2 alpha]] (alpha = c/m, w0^2 = k/m), so the Jacobian of the state at
t0 + s with respect to the state at t0 is the homogeneous fundamental matrix

    Phi(s) = e^{A s} = e^{-alpha s} [[C + alpha S, S], [-w0^2 S, C - alpha S]],

C, S as in :mod:`impactlib.flight` (cos/sin, 1/s, cosh/sinh for the three damping
regimes); it does not depend on the forcing, so resonance needs no special case.
det Phi(s) = e^{-2 alpha s}.  Its derivative with respect to the start TIME at a fixed
start state is -Phi(s) f(t0, y0) with f the vector field (y(t1; t0, y0) shifts with t0).

Saltation matrix
----------------
An impact at t_i is the crossing of the surface h(y) = x - g = 0 followed by the reset
y+ = R y- with R = diag(1, -r).  Perturbing the state before the impact moves the
impact time by dt = -n.dy / (n.f-) with n = (1, 0), so the Jacobian across the impact is
(Müller 1995; Leine & Nijmeijer 2004, ch. 7)

    S = R + (f+ - R f-) n^T / (n^T f-) = [[-r, 0], [(a+ + r a-) / v-, -r]],

f- = (v-, a-), f+ = (v+, a+) = (-r v-, a+), a the acceleration of Eq. (1) just before
and after.  det S = r^2.  As v- -> 0 (grazing) S blows up like 1/v-.

A mass stuck to the wall leaves it at a time fixed by the forcing alone
(flight.release_time), in the state (g, 0) whatever it was before: the Jacobian through a
sticking phase (and through a chatter summed to its accumulation point) is zero.

Identities (exact, used by the tests): over a stretch with m impacts and duration tau,
det J = r^(2 m) e^{-2 alpha tau}; hence the two Lyapunov exponents sum to
-2 c/m + 2 nu ln r, nu the number of impacts per unit time.

References
----------
P. C. Müller, "Calculation of Lyapunov exponents for dynamic systems with
discontinuities", Chaos, Solitons & Fractals 5 (1995) 1671-1681.
R. I. Leine and H. Nijmeijer, Dynamics and Bifurcations of Non-Smooth Mechanical
Systems, Springer (2004), ch. 7.
"""
from __future__ import annotations

import math

from ._jit import jit
from .flight import ALPHA, C_, G, K, LAM1, LAM2, M, OM, Q_, R, SQ, W0SQ


@jit
def damped_pair(sp, s):
    """(e^{-alpha s} C, e^{-alpha s} S) of the homogeneous flow, all damping regimes."""
    alpha = sp[ALPHA]
    q = sp[Q_]
    sq = sp[SQ]
    if q > 0.0:
        ex = math.exp(-alpha * s)
        return ex * math.cos(sq * s), ex * math.sin(sq * s) / sq
    if q == 0.0:
        ex = math.exp(-alpha * s)
        return ex, ex * s
    z = sq * s
    if z < 20.0:
        ex = math.exp(-alpha * s)
        return ex * math.cosh(z), ex * math.sinh(z) / sq
    e1 = math.exp(sp[LAM1] * s)
    e2 = math.exp(sp[LAM2] * s)
    return 0.5 * (e1 + e2), 0.5 * (e1 - e2) / sq


@jit
def flow_jacobian(sp, s):
    """Phi(s) = d(x, v)(t0 + s) / d(x, v)(t0) as (p11, p12, p21, p22)."""
    eC, eS = damped_pair(sp, s)
    alpha = sp[ALPHA]
    return eC + alpha * eS, eS, -sp[W0SQ] * eS, eC - alpha * eS


@jit
def saltation(sp, t, vm):
    """Saltation matrix of an impact at time t with velocity vm < 0 just before it,
    as (s11, s12, s21, s22) = (-r, 0, (a+ + r a-) / vm, -r)."""
    r = sp[R]
    m = sp[M]
    c2 = 2.0 * sp[C_]
    f = math.cos(sp[OM] * t) - sp[K] * sp[G]
    am = (f - c2 * vm) / m
    ap = (f + c2 * r * vm) / m
    if vm == 0.0:
        vm = -1e-300
    return -r, 0.0, (ap + r * am) / vm, -r


@jit
def _mul(a11, a12, a21, a22, b11, b12, b21, b22):
    return (a11 * b11 + a12 * b21, a11 * b12 + a12 * b22,
            a21 * b11 + a22 * b21, a21 * b12 + a22 * b22)


@jit
def _qr(j11, j12, j21, j22):
    """Gram-Schmidt of the columns: (q11, q12, q21, q22, log|R11|, log|R22|)."""
    r11 = math.hypot(j11, j21)
    if r11 == 0.0:
        return 1.0, 0.0, 0.0, 1.0, -math.inf, -math.inf
    q11 = j11 / r11
    q21 = j21 / r11
    r12 = q11 * j12 + q21 * j22
    w1 = j12 - r12 * q11
    w2 = j22 - r12 * q21
    r22 = math.hypot(w1, w2)
    if r22 == 0.0:
        return q11, -q21, q21, q11, math.log(r11), -math.inf
    return q11, w1 / r22, q21, w2 / r22, math.log(r11), math.log(r22)


#: bounds of the leading column's size before it is rescaled (by a power of 2, exactly)
COLUMN_BIG = 2.0 ** 256
COLUMN_SMALL = 2.0 ** -256


@jit
def column_scale(j11, j21):
    """(k, 2^-k) that bring the column (j11, j21) back to size 1 when it has left
    [COLUMN_SMALL, COLUMN_BIG]; (0, 1) while it has not (or is zero)."""
    a = max(abs(j11), abs(j21))
    if COLUMN_SMALL <= a <= COLUMN_BIG or a == 0.0:
        return 0.0, 1.0
    k = math.frexp(a)[1]
    return float(k), math.ldexp(1.0, -k)


@jit
def leading_logs(j11, j21, scaled, log_det):
    """The logs (log|R11|, log|R22|) that QR steps over a window would have summed, from
    the window's leading column (j11, j21) (the first column of J: only it grows like
    log|R11| sums), the log2 ``scaled`` of the powers of 2 taken out of it, and the log of
    |det J| over the window, log|R22| summing to log|det J| - log|R11|.  -inf for both
    where the column vanished (sticking)."""
    n = math.hypot(j11, j21)
    if n == 0.0:
        return -math.inf, -math.inf
    l1 = math.log(n) + scaled * math.log(2.0)
    return l1, log_det - l1


@jit
def tangent_product(a, jm):
    """jm <- A jm in place, A = (a11, a12, a21, a22), jm = [j11, j12, j21, j22]."""
    j11, j12, j21, j22 = _mul(a[0], a[1], a[2], a[3], jm[0], jm[1], jm[2], jm[3])
    jm[0], jm[1], jm[2], jm[3] = j11, j12, j21, j22


@jit
def qr_step(jm):
    """jm <- Q of jm = Q R in place; returns (log|R11|, log|R22|)."""
    q11, q12, q21, q22, l1, l2 = _qr(jm[0], jm[1], jm[2], jm[3])
    jm[0], jm[1], jm[2], jm[3] = q11, q12, q21, q22
    return l1, l2
