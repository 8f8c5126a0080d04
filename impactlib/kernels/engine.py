"""The one event loop: a run of Eq. (1) from a state to t_end by the closed form (exact)
or an integrator (rk4, rk45), optionally carrying the 2x2 tangent matrix along it.

Inputs are the system constants ``sp`` (:mod:`impactlib.flight`), a packed array of run
controls ``ctl`` (layout below), the start (t, x, v) and a :class:`Buffers` bundle the
run fills in place; the outcome comes back in a float array ``res`` (layout below), so
the kernel is callable from other jitted code and returns no long tuple.

The tangent (flow Jacobians between events, saltation matrices at impacts, zero through
sticking; :mod:`impactlib.tangent`) is carried when ctl[TANGENT] is JACOBIAN (J of the
final state with respect to the start) or QR_MARKS (J re-orthonormalised after every
impact and at the sorted times ``marks``; log|R11|, log|R22| between marks[i] and
marks[i + 1] summed in logs[i], J restarting as the identity at marks[0]) or LEADING
(the same logs from J's first column alone, rescaled by powers of 2 where it grows or
shrinks far, and |det J|, which is exp(-2 c/m) per time and r^2 per impact: no QR step
per impact; for the largest exponent of one window, where QR_MARKS's other bookkeeping
is not needed).

Numba counts references to arrays with atomic operations in every kernel taking arrays
that calls another kernel or stores in a branch; per impact they cost about as much as
the impact search itself.  So the exact method's loop passes the constants, the grid and
each segment as tuples (flight.py), takes its samples and records its impacts itself,
and the helpers it calls per impact with arrays read them before branching.
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ._jit import as_tuple, jit
from .chatter import STICK, impact_outcome
from .events import IMPACT, STEP_LIMIT
from .grid import NGRID, next_impact_grid, search_grid
from .flight import ALPHA, G, NSP, R, flight_state, make_segment, release_time
from .integrators import advance_rk4, advance_rk45
from ..model import RunStatus
from .tangent import (column_scale, flow_jacobian, leading_logs, qr_step, saltation,
                      tangent_product)

HOP_MEMORY = 8           # hops remembered for predicting the next one
HOP_MATCH_RTOL = 1e-3    # ... if it left the wall this close in speed
TAIL_TOL = 1e-6          # a chatter is summed at the latest once one hop lasts under this many time scales

#: method codes (ctl[METHOD])
METHOD_IDS = {"exact": 0, "rk4": 1, "rk45": 2}
EXACT, RK4, RK45 = 0, 1, 2
#: tangent modes (ctl[TANGENT])
NO_TANGENT, JACOBIAN, QR_MARKS, LEADING = 0, 1, 2, 3

# run controls layout (ctl)
T_END, T_RECORD, HMAX, RATE, DT, RTOL, ATOL, MAX_IMPACTS, MAX_STEPS, METHOD, TANGENT, NCTL = range(12)

# result layout (res): counts are whole numbers stored as floats
(STATUS, N_REC, N_TOT, N_STICK, N_TAIL, T_F, X_F, V_F, STUCK, NSTEPS, J11, J12, J21, J22,
 STUCK_MARKED, N_MARKED, VMIN, NRES) = range(18)

_OK = int(RunStatus.OK)
_IMPACT_LIMIT = int(RunStatus.IMPACT_LIMIT)
_STEP_LIMIT = int(RunStatus.STEP_LIMIT)
_OUTPUT_FULL = int(RunStatus.OUTPUT_FULL)

#: What a run fills in place: impacts in [t_record, t_end] (as many as imp_t holds; more
#: are counted, not kept, and flagged OUTPUT_FULL unless imp_t is empty), sticking intervals clipped to the window (n, 2), the state at
#: the sorted sample times pc_t and d_t (inside the window), the tangent's marks and the
#: logs of its QR steps (len(marks) - 1, 2).
Buffers = namedtuple("Buffers", "imp_t imp_v stick pc_t pc_x pc_v d_t d_x d_v marks logs")

_NONE = np.empty(0)
_NONE2 = np.empty((0, 2))


def buffers(imp_t=_NONE, imp_v=_NONE, stick=_NONE2, pc_t=_NONE, pc_x=_NONE, pc_v=_NONE,
            d_t=_NONE, d_x=_NONE, d_v=_NONE, marks=_NONE, logs=_NONE2):
    """A :data:`Buffers` bundle, empty where not given (Python side)."""
    return Buffers(imp_t, imp_v, stick, pc_t, pc_x, pc_v, d_t, d_x, d_v, marks, logs)


@jit
def no_buffers():
    """An empty :data:`Buffers` bundle (jitted side)."""
    e = np.empty(0)
    e2 = np.empty((0, 2))
    return Buffers(e, e, e2, e, e, e, e, e, e, e, e2)


@jit
def controls(t_end, t_record, hmax, rate, dt, rtol, atol, max_impacts, max_steps, method,
             tangent):
    """The packed run controls ``ctl``."""
    ctl = np.empty(NCTL)
    ctl[T_END], ctl[T_RECORD], ctl[HMAX], ctl[RATE] = t_end, t_record, hmax, rate
    ctl[DT], ctl[RTOL], ctl[ATOL] = dt, rtol, atol
    ctl[MAX_IMPACTS], ctl[MAX_STEPS] = max_impacts, max_steps
    ctl[METHOD], ctl[TANGENT] = method, tangent
    return ctl


@jit
def _sample_rest(g, t_hi, ts, xs, vs, i):
    while i < ts.shape[0] and ts[i] <= t_hi:
        xs[i] = g
        vs[i] = 0.0
        i += 1
    return i


@jit
def _record_impact(imp_t, imp_v, n_rec, t, vm, t_record):
    if t >= t_record:
        if n_rec < imp_t.shape[0]:
            imp_t[n_rec] = t
            imp_v[n_rec] = vm
        n_rec += 1
    return n_rec


@jit
def _next_report(t, t_end, pc_t, ip, d_t, idn, marks, im):
    """The next time after t the run reports a state (a sample, a mark or its end): a
    chatter's tail is summed early only if it ends before (chatter.impact_outcome)."""
    # each array read before any branch: Numba then drops the arrays' reference counting
    # (atomic operations), as in every helper the loop calls per impact
    tp = pc_t[ip] if ip < pc_t.shape[0] else math.inf
    td = d_t[idn] if idn < d_t.shape[0] else math.inf
    tm = marks[im] if im < marks.shape[0] else math.inf
    ts = t_end
    if tp > t:
        ts = min(ts, tp)
    if td > t:
        ts = min(ts, td)
    if tm > t:
        ts = min(ts, tm)
    return ts


@jit
def _tangent_to(sp, jm, t_to, tq, marks, logs, im, tmode, scaled, n_marked, n_at_mark):
    """Advance the tangent jm (4,) from tq to t_to through the marks on the way; returns
    (t_to, im, scaled, n_at_mark): LEADING's scale taken out of the leading column and the
    impact count at the last mark."""
    nm = marks.shape[0]
    while im < nm and marks[im] <= t_to:
        tangent_product(flow_jacobian(sp, marks[im] - tq), jm)
        tq = marks[im]
        if tmode == QR_MARKS:
            if im == 0:
                jm[0], jm[1], jm[2], jm[3] = 1.0, 0.0, 0.0, 1.0
            else:
                l1, l2 = qr_step(jm)
                logs[im - 1, 0] += l1
                logs[im - 1, 1] += l2
        elif tmode == LEADING:
            if im > 0:
                log_det = -2.0 * sp[ALPHA] * (marks[im] - marks[im - 1])
                if n_marked > n_at_mark:
                    log_det += (n_marked - n_at_mark) * 2.0 * math.log(sp[R])
                l1, l2 = leading_logs(jm[0], jm[2], scaled, log_det)
                logs[im - 1, 0] += l1
                logs[im - 1, 1] += l2
            n = math.hypot(jm[0], jm[2])
            if im == 0 or n == 0.0:
                jm[0], jm[2] = 1.0, 0.0
            else:
                jm[0], jm[2] = jm[0] / n, jm[2] / n
            jm[1], jm[3] = 0.0, 0.0
            scaled = 0.0
            n_at_mark = n_marked
        im += 1
    tangent_product(flow_jacobian(sp, t_to - tq), jm)
    return t_to, im, scaled, n_at_mark


@jit
def run_engine(sp, ctl, t, x, v, buf, res):
    """Drive one run from the state (t, x, v) to ctl[T_END]; see the module docstring.

    res (length NRES) receives the status (:class:`impactlib.model.RunStatus`), the
    impacts recorded in the window and in all, the sticking intervals kept, the chatter
    sequences summed to their accumulation point in the window, the final state (t, x, v,
    stuck), the steps spent, the tangent (J11, J12, J21, J22; zero after sticking), and,
    relative to marks[0] (all of the run without marks): whether the mass sticks after it,
    the impacts after it and the smallest |v-| among them.
    """
    g = sp[G]
    r = sp[R]
    t_end = ctl[T_END]
    t_record = ctl[T_RECORD]
    hmax = ctl[HMAX]
    rate = ctl[RATE]
    max_impacts = ctl[MAX_IMPACTS]
    max_steps = int(ctl[MAX_STEPS])
    method = int(ctl[METHOD])
    tmode = int(ctl[TANGENT])
    tangent = tmode != NO_TANGENT
    qr = tmode == QR_MARKS
    lead = tmode == LEADING
    # QR_MARKS and LEADING restart the tangent at marks[0]: none is carried before
    marked = qr or lead
    scaled = 0.0      # LEADING: log2 of the scale taken out of the leading column
    n_at_mark = 0     # LEADING: impacts after marks[0] at the last mark
    pc_t, pc_x, pc_v = buf.pc_t, buf.pc_x, buf.pc_v
    d_t, d_x, d_v = buf.d_t, buf.d_x, buf.d_v
    stick = buf.stick
    marks = buf.marks
    logs = buf.logs
    imp_t, imp_v = buf.imp_t, buf.imp_v
    cap = imp_t.shape[0]
    nm = marks.shape[0]
    n_rec = 0
    n_tot = 0
    n_stick = 0
    n_tail = 0
    nsteps = 0
    ip = 0
    idn = 0
    status = _OK
    stuck = False
    stuck_marked = False
    n_marked = 0
    vmin = math.inf
    jm = np.zeros(4)
    jm[0] = 1.0
    jm[3] = 1.0
    tq = t            # time the tangent has reached
    im = 0            # next mark
    t_mark0 = marks[0] if nm > 0 else -math.inf
    h45 = min(0.01 / rate, hmax)
    grid = search_grid(sp, rate) if method == EXACT else np.zeros(NGRID)
    # the constants, the grid and each segment as tuples in the exact method's loop
    # (flight.py): no reference counting per impact
    spt = as_tuple(sp, NSP)
    gridt = as_tuple(grid, NGRID)
    # the last hops (rebound speed, length): a hop that left the wall as fast as this one
    # predicts its length (periodic orbits repeat them)
    hop_v = np.full(HOP_MEMORY, -1.0)
    hop_s = np.zeros(HOP_MEMORY)
    n_hop = 0
    # the initial state may be on the wall
    if x <= g:
        x = g
        if v < 0.0:
            n_rec = _record_impact(imp_t, imp_v, n_rec, t, v, t_record)
            n_tot += 1
            if tangent:
                tangent_product(saltation(spt, t, v), jm)
            v = -r * v
        if v <= 0.0:
            v = 0.0
        mode, tn = impact_outcome(spt, t, v, rate, TAIL_TOL,
                                  _next_report(t, t_end, pc_t, ip, d_t, idn, marks, im))
        if mode == STICK:
            ip = _sample_rest(g, tn, pc_t, pc_x, pc_v, ip)
            idn = _sample_rest(g, tn, d_t, d_x, d_v, idn)
            t = tn
            v = 0.0
            stuck = True
    while True:
        if stuck:
            # the tangent follows the state: zero through sticking, whatever came before
            tr = release_time(spt, t)
            te = min(tr, t_end)
            ip = _sample_rest(g, te, pc_t, pc_x, pc_v, ip)
            idn = _sample_rest(g, te, d_t, d_x, d_v, idn)
            if te > max(t, t_record) and n_stick < stick.shape[0]:
                stick[n_stick, 0] = max(t, t_record)
                stick[n_stick, 1] = te
                n_stick += 1
            if te > t_mark0:
                stuck_marked = True
            jm[:] = 0.0
            while im < nm and marks[im] <= te:
                if qr and im == 0:
                    jm[0], jm[1], jm[2], jm[3] = 1.0, 0.0, 0.0, 1.0
                im += 1
                scaled = 0.0
                n_at_mark = n_marked
            jm[:] = 0.0
            tq = te
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
        started_at_rest = False
        if method == EXACT:
            seg = make_segment(spt, t, x, v)
            guess = -1.0
            best = HOP_MATCH_RTOL * v
            for jh in range(HOP_MEMORY):
                if abs(hop_v[jh] - v) < best:
                    best = abs(hop_v[jh] - v)
                    guess = hop_s[jh]
            kind, s, vh, ns = next_impact_grid(spt, seg, t_end - t, hmax, max_steps - nsteps,
                                               gridt, guess)
            if kind == IMPACT and v > 0.0:
                hop_v[n_hop % HOP_MEMORY] = v
                hop_s[n_hop % HOP_MEMORY] = s
                n_hop += 1
            th = t + s
            # samples in the loop itself: a helper taking the arrays would pay their
            # reference counting (atomic) on every flight
            while ip < pc_t.shape[0] and pc_t[ip] <= th:
                pc_x[ip], pc_v[ip] = flight_state(spt, seg, pc_t[ip] - t)[:2]
                ip += 1
            while idn < d_t.shape[0] and d_t[idn] <= th:
                d_x[idn], d_v[idn] = flight_state(spt, seg, d_t[idn] - t)[:2]
                idn += 1
            started_at_rest = s == 0.0 and x <= g and v == 0.0
            xh, vend = g, vh
            if kind != IMPACT:
                xh, vend, ae, je, rhe, sce = flight_state(spt, seg, s)
        elif method == RK4:
            kind, th, xh, vh, ns, ip, idn = advance_rk4(
                sp, t, x, v, t_end, ctl[DT], pc_t, pc_x, pc_v, ip, d_t, d_x, d_v, idn,
                max_steps - nsteps)
            vend = vh
        else:
            kind, th, xh, vh, h45, ns, ip, idn = advance_rk45(
                sp, t, x, v, h45, t_end, ctl[RTOL], ctl[ATOL], pc_t, pc_x, pc_v, ip, d_t, d_x,
                d_v, idn, max_steps - nsteps)
            vend = vh
        nsteps += ns
        if tangent:
            if im < nm and marks[im] <= th:
                tq, im, scaled, n_at_mark = _tangent_to(spt, jm, th, tq, marks, logs, im, tmode,
                                                        scaled, n_marked, n_at_mark)
            elif not (marked and im == 0 and nm > 0):
                tangent_product(flow_jacobian(spt, th - tq), jm)
                tq = th
        if kind != IMPACT:
            # reached t_end, or stopped at the step limit: (th, xh, vend) is where
            t, x, v = th, xh, vend
            if kind == STEP_LIMIT:
                status = _STEP_LIMIT
            break
        # impact at th with velocity vh <= 0
        t = th
        x = g
        if not (started_at_rest and vh == 0.0):
            n_tot += 1
            # recorded here, not by _record_impact: a helper storing into the arrays
            # pays their reference counting (atomic) on every impact
            if t >= t_record:
                if n_rec < cap:
                    imp_t[n_rec] = t
                    imp_v[n_rec] = vh
                n_rec += 1
            if t >= t_mark0:
                n_marked += 1
                vmin = min(vmin, -vh)
            if tangent and not (marked and im == 0 and nm > 0):
                tangent_product(saltation(spt, t, vh), jm)
                if qr:
                    # every impact from marks[0] on (after the window only overflow matters)
                    l1, l2 = qr_step(jm)
                    if 0 < im < nm:
                        logs[im - 1, 0] += l1
                        logs[im - 1, 1] += l2
                elif lead:
                    k, scale = column_scale(jm[0], jm[2])
                    if k != 0.0:
                        jm[0] *= scale
                        jm[2] *= scale
                        scaled += k
        vplus = -r * vh
        if vplus <= 0.0:
            vplus = 0.0
        mode, tn = impact_outcome(spt, t, vplus, rate, TAIL_TOL,
                                  _next_report(t, t_end, pc_t, ip, d_t, idn, marks, im))
        if mode == STICK:
            if tn > t and t >= t_record:
                n_tail += 1
            ip = _sample_rest(g, tn, pc_t, pc_x, pc_v, ip)
            idn = _sample_rest(g, tn, d_t, d_x, d_v, idn)
            t = tn
            v = 0.0
            stuck = True
        else:
            v = vplus
        if n_tot >= max_impacts:
            status = _IMPACT_LIMIT
            break
        if nsteps >= max_steps:
            status = _STEP_LIMIT
            break
    # the marks left (at t_end) when the run ended in flight
    if tangent and not stuck and status == _OK and im < nm:
        while im < nm and marks[im] <= t_end:
            tq, im, scaled, n_at_mark = _tangent_to(spt, jm, marks[im], tq, marks, logs, im,
                                                    tmode, scaled, n_marked, n_at_mark)
    if stuck:
        jm[:] = 0.0
    if status == _OK and 0 < cap < n_rec:
        # an empty imp_t asks for the counts only
        status = _OUTPUT_FULL
    res[STATUS] = status
    res[N_REC] = n_rec
    res[N_TOT] = n_tot
    res[N_STICK] = n_stick
    res[N_TAIL] = n_tail
    res[T_F] = t
    res[X_F] = x
    res[V_F] = v
    res[STUCK] = 1.0 if stuck else 0.0
    res[NSTEPS] = nsteps
    res[J11], res[J12], res[J21], res[J22] = jm[0], jm[1], jm[2], jm[3]
    res[STUCK_MARKED] = 1.0 if stuck_marked else 0.0
    res[N_MARKED] = n_marked
    res[VMIN] = vmin
    return status


@jit
def run_from_python(sp, ctl, t, x, v, imp_t, imp_v, stick, pc_t, pc_x, pc_v, d_t, d_x, d_v,
                    marks, logs, res):
    """:func:`run_engine` with the buffers as separate arrays: the entry from Python, since
    Numba's dispatcher types a tuple of arrays much more slowly than the arrays."""
    return run_engine(sp, ctl, t, x, v, Buffers(imp_t, imp_v, stick, pc_t, pc_x, pc_v, d_t,
                                                  d_x, d_v, marks, logs), res)
