"""Tangent dynamics of the impact oscillator: flow Jacobians, saltation matrices, and a
run that carries a 2x2 tangent matrix along the exact trajectory.

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
from .events import IMPACT, STEP_LIMIT, STICK, impact_outcome, next_impact
from .flight import (ALPHA, C_, G, K, LAM1, LAM2, M, OM, Q_, R, SQ, W0SQ, flight_state,
                     release_time, start_segment)
from .simulate import TAIL_TOL

# tangent_run status codes (as simulate.run_kernel)
RUN_OK, RUN_IMPACT_LIMIT, RUN_STEP_LIMIT = 0, 1, 2


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


@jit
def tangent_run(sp, t, x, v, t_end, t_record, hmax, rate, marks, qr, imp_t, imp_v, logs,
                max_impacts, max_steps):
    """The exact run of simulate.run_kernel (method "exact") from (t, x, v) to t_end,
    carrying the tangent matrix J along it.

    With ``qr`` False, J is the Jacobian of the final state with respect to the initial
    one (the product of flow Jacobians and saltation matrices; zero after sticking).
    With ``qr`` True, J is re-orthonormalised after every impact and at each of the sorted
    times ``marks`` (inside [t, t_end]); J restarts as the identity at marks[0], and
    log|R11|, log|R22| of the QR steps between marks[i] and marks[i+1] add up in logs[i].

    Impacts inside [t_record, t_end] go to imp_t, imp_v (as many as they hold).

    Returns
    -------
    (status, n_rec, n_tot, t, x, v, stuck, nsteps, j11, j12, j21, j22, stuck_marked,
     n_marked, vmin, n_tail) : stuck_marked is True when the mass sticks at some time after
     marks[0] (the exponents are -inf), n_marked counts the impacts after marks[0],
     vmin is the smallest |v-| of the impacts after marks[0] (of all, without marks),
     n_tail counts the chatters summed to their accumulation point.
    """
    g = sp[G]
    r = sp[R]
    cap = imp_t.shape[0]
    nm = marks.shape[0]
    n_rec = 0
    n_tot = 0
    nsteps = 0
    status = RUN_OK
    stuck = False
    stuck_marked = False
    n_marked = 0
    n_tail = 0
    vmin = math.inf
    j11, j12, j21, j22 = 1.0, 0.0, 0.0, 1.0
    tq = t            # time the tangent has reached
    im = 0            # next mark
    if nm == 0:
        t_mark0 = -math.inf
    else:
        t_mark0 = marks[0]
    # the initial state may be on the wall (as run_kernel)
    if x <= g:
        x = g
        if v < 0.0:
            if t >= t_record:
                if n_rec < cap:
                    imp_t[n_rec] = t
                    imp_v[n_rec] = v
                n_rec += 1
            n_tot += 1
            s11, s12, s21, s22 = saltation(sp, t, v)
            j11, j12, j21, j22 = _mul(s11, s12, s21, s22, j11, j12, j21, j22)
            v = -r * v
        if v <= 0.0:
            v = 0.0
        mode, tn = impact_outcome(sp, t, v, rate, TAIL_TOL)
        if mode == STICK:
            t = tn
            v = 0.0
            stuck = True
            j11, j12, j21, j22 = 0.0, 0.0, 0.0, 0.0
    while True:
        # the tangent follows the state: when stuck its time is the stuck state's
        if stuck:
            tr = release_time(sp, t)
            te = min(tr, t_end)
            if te > t_mark0:
                stuck_marked = True
            j11, j12, j21, j22 = 0.0, 0.0, 0.0, 0.0
            while im < nm and marks[im] <= te:
                if qr and im == 0:
                    j11, j12, j21, j22 = 1.0, 0.0, 0.0, 1.0
                im += 1
            tq = te
            j11, j12, j21, j22 = 0.0, 0.0, 0.0, 0.0
            if tr >= t_end:
                t = t_end
                break
            t = tr
            x = g
            v = 0.0
            stuck = False
            continue
        if t >= t_end:
            break
        seg = start_segment(sp, t, x, v)
        kind, s, vh, ns = next_impact(sp, seg, t_end - t, hmax, max_steps - nsteps)
        th = t + s
        started_at_rest = s == 0.0 and x <= g and v == 0.0
        nsteps += ns
        # the tangent up to th, through the marks on the way
        while im < nm and marks[im] <= th:
            p11, p12, p21, p22 = flow_jacobian(sp, marks[im] - tq)
            j11, j12, j21, j22 = _mul(p11, p12, p21, p22, j11, j12, j21, j22)
            tq = marks[im]
            if qr:
                if im == 0:
                    j11, j12, j21, j22 = 1.0, 0.0, 0.0, 1.0
                else:
                    j11, j12, j21, j22, l1, l2 = _qr(j11, j12, j21, j22)
                    logs[im - 1, 0] += l1
                    logs[im - 1, 1] += l2
            im += 1
        p11, p12, p21, p22 = flow_jacobian(sp, th - tq)
        j11, j12, j21, j22 = _mul(p11, p12, p21, p22, j11, j12, j21, j22)
        tq = th
        if kind != IMPACT:
            x, v, ae, je, rhe, sce = flight_state(sp, seg, s)
            t = th
            if kind == STEP_LIMIT:
                status = RUN_STEP_LIMIT
            break
        t = th
        x = g
        if not (started_at_rest and vh == 0.0):
            n_tot += 1
            if t >= t_record:
                if n_rec < cap:
                    imp_t[n_rec] = t
                    imp_v[n_rec] = vh
                n_rec += 1
            if t >= t_mark0:
                n_marked += 1
                vmin = min(vmin, -vh)
            s11, s12, s21, s22 = saltation(sp, t, vh)
            j11, j12, j21, j22 = _mul(s11, s12, s21, s22, j11, j12, j21, j22)
            if qr:
                # every impact (also in the transient, where only overflow matters)
                j11, j12, j21, j22, l1, l2 = _qr(j11, j12, j21, j22)
                if 0 < im < nm:
                    logs[im - 1, 0] += l1
                    logs[im - 1, 1] += l2
        vplus = -r * vh
        if vplus <= 0.0:
            vplus = 0.0
        mode, tn = impact_outcome(sp, t, vplus, rate, TAIL_TOL)
        if mode == STICK:
            if tn > t:
                n_tail += 1
            t = tn
            v = 0.0
            stuck = True
        else:
            v = vplus
        if n_tot >= max_impacts:
            status = RUN_IMPACT_LIMIT
            break
        if nsteps >= max_steps:
            status = RUN_STEP_LIMIT
            break
    # remaining marks (at t_end) when the run ended in flight
    while im < nm and marks[im] <= t_end and not stuck and status == RUN_OK:
        p11, p12, p21, p22 = flow_jacobian(sp, marks[im] - tq)
        j11, j12, j21, j22 = _mul(p11, p12, p21, p22, j11, j12, j21, j22)
        tq = marks[im]
        if qr:
            if im == 0:
                j11, j12, j21, j22 = 1.0, 0.0, 0.0, 1.0
            else:
                j11, j12, j21, j22, l1, l2 = _qr(j11, j12, j21, j22)
                logs[im - 1, 0] += l1
                logs[im - 1, 1] += l2
        im += 1
    if stuck:
        j11, j12, j21, j22 = 0.0, 0.0, 0.0, 0.0
    return (status, n_rec, n_tot, t, x, v, stuck, nsteps, j11, j12, j21, j22, stuck_marked,
            n_marked, vmin, n_tail)
