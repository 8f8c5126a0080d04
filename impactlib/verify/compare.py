"""Impact matching and error metrics: one solution's impacts against a reference's.

Shared by the accuracy report (:mod:`impactlib.report`, against the mpmath reference) and
the app's accuracy readout (against the exact method).  Needs only numpy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: chatter impacts slower than this fraction of the largest impact speed form the tail
#: that the exact method sums instead of resolving (compared through its end time)
V_FLOOR = 1e-4


@dataclass
class Comparison:
    compared: int = 0          # reference impacts compared one by one
    err_t: float = 0.0         # max |t - t_ref|
    err_v: float = 0.0         # max |v - v_ref| / V (V = largest reference impact speed)
    v_scale: float = 0.0
    missed: int = 0
    extra: int = 0
    err_stick: float = math.nan   # max |start - start_ref| of the sticking intervals
    err_state: float = math.nan   # dense cases: max |x - x_ref|, |v - v_ref|
    tail: int = 0              # reference chatter impacts below the floor (summed by the solver)


def match_impacts(ref_t, ref_v, t, v, v_floor=0.0):
    """Match impacts by time: each reference impact to the nearest unused method impact
    within half the gap to its neighbouring reference impacts.

    Reference impacts slower than ``v_floor`` (the tail of a chatter, which the solver
    sums instead of resolving) take part in the matching but are not required.

    Returns (pairs, missed, extra, tail): index pairs (i_ref, i_method) of matched impacts
    with |v_ref| >= v_floor; the number of such reference impacts without a partner; of
    method impacts with |v| >= v_floor without one; and of unmatched slow reference impacts.
    """
    ref_t = np.asarray(ref_t, dtype=float)
    ref_v = np.asarray(ref_v, dtype=float)
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    n = ref_t.size
    gaps = np.diff(ref_t)
    left = np.concatenate([[np.inf], gaps])
    right = np.concatenate([gaps, [np.inf]])
    win = 0.5 * np.minimum(left, right)
    win = np.where(np.isfinite(win), win, 1.0)
    used = np.zeros(t.size, dtype=bool)
    pairs = []
    missed = 0
    tail = 0
    for i in range(n):
        best = None
        if t.size:
            j = int(np.searchsorted(t, ref_t[i]))
            for jj in (j - 1, j, j + 1):
                if 0 <= jj < t.size and not used[jj] and abs(t[jj] - ref_t[i]) < win[i]:
                    if best is None or abs(t[jj] - ref_t[i]) < abs(t[best] - ref_t[i]):
                        best = jj
        if best is not None:
            used[best] = True
        slow = abs(ref_v[i]) < v_floor
        if best is None:
            if slow:
                tail += 1
            else:
                missed += 1
        elif not slow:
            pairs.append((i, best))
    extra = int(np.sum(~used & (np.abs(v) >= v_floor)))
    return pairs, missed, extra, tail


def impact_errors(ref_t, ref_v, t, v, v_floor=V_FLOOR) -> Comparison:
    """Match impacts (t, v) to the reference's (:func:`match_impacts`, the reference's
    impacts slower than v_floor times its largest speed V being the chatter tail) and
    return the counts and the largest errors: |t - t_ref| and |v - v_ref| / V."""
    ref_t = np.asarray(ref_t, dtype=float)
    ref_v = np.asarray(ref_v, dtype=float)
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    out = Comparison()
    V = float(np.max(np.abs(ref_v))) if ref_v.size else 0.0
    out.v_scale = V
    pairs, missed, extra, tail = match_impacts(ref_t, ref_v, t, v, v_floor * V)
    out.compared, out.missed, out.extra, out.tail = len(pairs), missed, extra, tail
    if pairs:
        i, j = np.array(pairs).T
        out.err_t = float(np.max(np.abs(t[j] - ref_t[i])))
        out.err_v = float(np.max(np.abs(v[j] - ref_v[i]))) / V
    return out


__all__ = ["V_FLOOR", "Comparison", "match_impacts", "impact_errors"]
