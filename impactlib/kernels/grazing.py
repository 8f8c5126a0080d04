"""The lowest point of a flight: where an orbit's flight comes closest to the wall
between impacts, as the grazing tests of :func:`impactlib.boundary` watch it."""
from __future__ import annotations

import math

from ._jit import jit
from .flight import G, flight_state

#: Minima this close (relative to the flight's length) to an impact or to the touch are
#: the touch itself, not another minimum.
ENDS_MARGIN = 1e-6
#: Samples per flight at which the sign of v is checked for a minimum.
CLEARANCE_SAMPLES = 48


@jit
def lowest_in_flight(sp, seg, duration, skip, nsamp):
    """(x - g, s) at the lowest interior minimum of a flight (inf when none), minima
    within ENDS_MARGIN of its ends or of time ``skip`` (nan: none) left out."""
    margin = ENDS_MARGIN * duration
    h = duration / nsamp
    best, where = math.inf, math.nan
    vp = flight_state(sp, seg, 0.0)[1]
    for i in range(1, nsamp + 1):
        v = flight_state(sp, seg, i * h)[1]
        if vp < 0.0 <= v:
            lo, hi = (i - 1) * h, i * h
            sm = 0.5 * (lo + hi)
            for _ in range(60):        # bisection with Newton steps on v = 0
                _, vm, am, _, _, _ = flight_state(sp, seg, sm)
                if vm < 0.0:
                    lo = sm
                else:
                    hi = sm
                sn = sm - vm / am if am > 0.0 else 0.5 * (lo + hi)
                if not (lo < sn < hi):
                    sn = 0.5 * (lo + hi)
                if abs(sn - sm) <= 1e-15 * (1.0 + duration):
                    sm = sn
                    break
                sm = sn
            near = sm < margin or sm > duration - margin or abs(sm - skip) < margin
            xm = flight_state(sp, seg, sm)[0] - sp[G]
            if not near and xm < best:
                best, where = xm, sm
        vp = v
    return best, where
