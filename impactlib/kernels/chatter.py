"""What follows an impact: flight, rest on the wall, or the rest of a chatter summed.

A chatter is the sequence of ever shorter hops after an impact with a slow rebound; its
hops accumulate at a finite time, where the mass comes to rest on the wall.  The hops are
resolved one by one (kernels/events.py) until the rest can be summed with an error
bounded at rounding level (:func:`tail_bound`).
"""
from __future__ import annotations

import math

from ._jit import jit
from .events import EPS
from .flight import C_, G, K, M, OM, R, release_time, wall_force

#: impact_outcome's modes
FLY, STICK = 0, 1

#: a chatter is not tested for early summation while its hop lasts over this many time
#: scales: the bound is met far below (hops of ~1e-5 time scales at t ~ 1e2, growing like
#: t^(1/3)), so this spares its cost after most impacts
TAIL_CHECK = 1e-2
#: the tail's remainder bound must hold on an interval this many times the tail's estimate
TAIL_SPAN = 1.25
#: largest relative change of a speed over one hop that tail_bound assumes (and checks)
TAIL_DELTA = 0.25


@jit
def tail_bound(sp, t, v0):
    """The rest of a chatter from an impact at t with rebound v0 > 0, summed.

    Over one hop from the wall (speed v out, w back) Eq. (1) with y = x - g,
    y'' = -A(t) - b y' - q y (A = (k g - cos(omega t)) / m the push into the wall,
    b = 2 c / m, q = k / m), gives two exact identities (y = 0 at both ends):

        int_hop A dt = v + w - q int_hop y dt                    (impulse)
        w^2 - v^2 = 2 int_hop A' y dt - 2 b int_hop y'^2 dt       (energy)

    Summed over all hops (v_(n+1) = r w_(n+1), d_n = w_(n+1) - v_n, D = sum d_n,
    Y = int y):  F(t_inf) - F(t) = 2 v0 / (1 - r) + (1 + r) D / (1 - r) - q Y, F' = A
    (Budd & Dux 1994 keep the first term).  With the deceleration -y'' in [dl, dh] over
    the tail, int y and int y'^2 lie between (v^3 + w^3) / 3 times 1 / dh^2 .. 1 / dl^2
    and 1 / dh .. 1 / dl, so d_n = (2/3) G v_n^2 + O(v^3), G = (A' - b A) / A^2 at t,
    and v_n = r^n v0 (1 + O(v0)).  The target summed here is
    Phi = 2 v0 / (1 - r) + (2/3) G v0^2 / (1 - r)^2, and |F(t_inf) - F(t) - Phi| <= B,
    B the O(v0^3) sum of every neglected term, bounded rigorously with A, A' and
    A'' = omega^2 cos / m bounded over I = [t, t + TAIL_SPAN * estimate] (A > 0 there,
    the hops' speeds shrink at least by q = r (1 + delta) < 1 and end inside I); the
    accumulation time's error is then at most B / min_I A.

    Returns (ok, target, err, tb): ok False where those conditions fail; the target Phi,
    the bound err = B / min_I A on the accumulation time's error, and I's length tb
    (:func:`tail_length` solves for t_inf).
    """
    m, om, r = sp[M], sp[OM], sp[R]
    beta = 2.0 * sp[C_] / m
    kap = sp[K] / m
    kg = sp[K] * sp[G]
    cs = math.cos(om * t)
    a0 = (kg - cs) / m
    if not (r < 1.0 and a0 > 0.0 and v0 > 0.0):
        return False, 0.0, math.inf, 0.0
    a1 = om * math.sin(om * t) / m
    a2 = om * om / m
    tb = TAIL_SPAN * 2.0 * v0 / ((1.0 - r) * a0)
    spread = abs(a1) * tb + 0.5 * a2 * tb * tb
    amin = a0 - spread
    amax = a0 + spread
    if not amin > 0.0:
        return False, 0.0, math.inf, 0.0
    # deceleration bounds on every hop (|y'| <= u0 = (1 + delta) v0, height <= u0^2 / amin)
    delta = TAIL_DELTA
    u0 = (1.0 + delta) * v0
    h0 = u0 * u0 / amin
    dl = amin - beta * u0 - kap * h0
    dh = amax + beta * u0 + kap * h0
    if not dl > 0.5 * amin:
        return False, 0.0, math.inf, 0.0
    g0 = (a1 - beta * a0) / (a0 * a0)
    e1 = (abs(a1) * max(abs(1.0 / (dl * dl) - 1.0 / (a0 * a0)), abs(1.0 / (dh * dh) - 1.0 / (a0 * a0)))
          + beta * max(abs(1.0 / dl - 1.0 / a0), abs(1.0 / dh - 1.0 / a0)) + a2 * tb / (dl * dl))
    # |d| <= k0 v^2 on every hop, consistent with |d| <= delta v
    k0 = (2.0 / 3.0) * (abs(g0) + e1) * (1.0 + delta + delta * delta)
    dn = k0 * v0
    if not dn < delta:
        return False, 0.0, math.inf, 0.0
    q = r * (1.0 + dn)
    if not q < 1.0 or (2.0 + dn) * v0 / (dl * (1.0 - q)) > tb:
        return False, 0.0, math.inf, 0.0
    v2 = v0 * v0
    v3 = v2 * v0
    lg = k0 * v0 / ((1.0 - q) * (1.0 - dn))
    bd = (2.0 / 3.0) * (e1 * (1.0 + dn + dn * dn) * v2 / (1.0 - q * q)
                        + abs(g0) * k0 * (1.0 + dn) * v3 / (1.0 - q * q * q)
                        + abs(g0) * v2 * math.expm1(2.0 * lg) / (1.0 - r * r))
    by = kap * (1.0 + (1.0 + dn) ** 3) * v3 / (3.0 * dl * dl * (1.0 - q * q * q))
    err = ((1.0 + r) / (1.0 - r) * bd + by) / amin
    target = 2.0 * v0 / (1.0 - r) + (2.0 / 3.0) * g0 * v2 / ((1.0 - r) * (1.0 - r))
    if not (target > 0.0 and target <= amin * tb):
        return False, 0.0, math.inf, 0.0
    return True, target, err, tb


@jit
def tail_floor_terms(sp, v0, a0):
    """A lower bound of :func:`tail_bound`'s err from two of its terms alone, without
    trigonometry: where it exceeds the tolerance the bound need not be computed.

    Its A'' term gives e1 >= (omega^2 / m) tb / dl^2, so err >= (2/3) e1 v0^2 /
    ((1 - r)^2 a0); its spring term err >= 2 q v0^3 / (3 a0^3) (dl <= min A <= a0,
    q >= r).  a0 > 0 is the push A at the impact.  Returns (floor, tb)."""
    r, m = sp[R], sp[M]
    tb = TAIL_SPAN * 2.0 * v0 / ((1.0 - r) * a0)
    low = v0 * v0 / (a0 * a0 * a0) * ((2.0 / 3.0) * sp[OM] * sp[OM] / m * tb / ((1.0 - r) * (1.0 - r))
                                      + (2.0 / 3.0) * sp[K] / m * v0)
    return low, tb


@jit
def tail_length(sp, t, target, tb):
    """The root tau in (0, tb] of F(t + tau) - F(t) = target (:func:`tail_bound`; F' = A
    is at least its positive minimum there, so the root is unique); -1 if Newton leaves
    the interval."""
    m, om = sp[M], sp[OM]
    kg = sp[K] * sp[G]
    tau = target / ((kg - math.cos(om * t)) / m)
    for _ in range(30):
        # int_t^{t+tau} A = (kg tau - (sin(om(t+tau)) - sin(om t)) / om) / m
        half = 0.5 * om * tau
        dsin = 2.0 * math.cos(om * t + half) * math.sin(half)
        gval = (kg * tau - dsin / om) / m - target
        step = gval / ((kg - math.cos(om * (t + tau))) / m)
        tau -= step
        if not 0.0 < tau <= tb:
            return -1.0
        if abs(step) <= 4.0 * EPS * (abs(t) + tau):
            break
    return tau


@jit
def impact_outcome(sp, t, vplus, rate, tail_tol, t_stop):
    """What follows an impact at time t with rebound velocity vplus = -r v(t-) >= 0.

    Returns (mode, t_next): FLY from t (vplus > 0, or at rest with the force pushing
    off), or STICK from t_next.  The rest of a chatter (infinitely many hops) is summed
    (:func:`tail_bound`, :func:`tail_length`) as soon as the bound on the accumulation
    time's error is at rounding level, 4 eps (|t| + tau) as for an impact time, unless the
    tail would pass t_stop (the next time the run reports a state: its hops are resolved
    up to there instead, since a summed tail reports the mass at rest); at the latest
    once one hop lasts under tail_tol time scales (its error is then O(vplus^3), far below
    the hop's own rounding).  The mass sticks at t + tau, provided the push has not
    turned outwards by then.
    """
    r = sp[R]
    if vplus <= 0.0:
        tr = release_time(sp, t)
        if tr <= t:
            return FLY, t
        return STICK, t
    m = sp[M]
    push = -wall_force(sp, t) / m
    a0 = push + 2.0 * sp[C_] * vplus / m
    if not (r < 1.0 and push > 0.0 and 2.0 * vplus * rate <= TAIL_CHECK * a0):
        return FLY, t
    late = 2.0 * vplus * rate <= tail_tol * a0
    if not late:
        low, tb = tail_floor_terms(sp, vplus, push)
        if low > 4.0 * EPS * (abs(t) + tb):
            return FLY, t
    ok, target, err, tb = tail_bound(sp, t, vplus)
    # target / a0 is tau to first order (tau >= target / max A would be strict)
    if not ok or not (late or err <= 4.0 * EPS * (abs(t) + target / a0)):
        return FLY, t
    tau = tail_length(sp, t, target, tb)
    if not tau > 0.0:
        return FLY, t
    ts = t + tau
    if not late and ts > t_stop:
        return FLY, t
    if release_time(sp, t) > ts and wall_force(sp, ts) <= 0.0:
        return STICK, ts
    return FLY, t


__all__ = ["FLY", "STICK", "tail_bound", "tail_floor_terms", "tail_length", "impact_outcome", "TAIL_CHECK",
           "TAIL_SPAN", "TAIL_DELTA"]
