"""Work limits end a run with complete partial results and a message, never a hang."""
import numpy as np

import impactlib as il

from core_helpers import PAPER


def test_impact_limit_keeps_every_impact_up_to_where_it_stopped():
    """Regression: a run stopped by max_impacts with more impacts in the window than the
    first output buffer (1024) returned only the first 1024, though its message said
    'results up to t = ...'."""
    p = PAPER.replace(omega=0.2, r=0.95)           # ~300 chatter impacts per period
    full = il.simulate(p, t_end=500.0, t_record=0.0)
    lim = il.simulate(p, t_end=500.0, t_record=0.0, max_impacts=2000)
    assert full.status == 0 and full.n_impacts > 2000
    assert lim.status == 1 and not lim.success and "impact limit" in lim.message
    assert lim.n_impacts == len(lim.impacts) == 2000
    assert lim.impacts.t[-1] == lim.final[0]
    np.testing.assert_array_equal(lim.impacts.t, full.impacts.t[:2000])


def test_step_limit_reports_where_it_stopped():
    sol = il.simulate(PAPER, t_end=500.0, t_record=0.0, method="rk4", dt=1e-3, max_steps=1000)
    assert sol.status == 2 and "step limit" in sol.message
    assert sol.final[0] < 500.0
    assert np.all(sol.impacts.t <= sol.final[0])


def test_elastic_damped_bouncing_is_bounded_by_the_impact_limit():
    """r = 1 with damping, pressed against the wall: hops shrink like 1/n, so impacts pile
    up without a finite accumulation point (no geometric tail to sum).  The run must end
    at the impact limit with a status, not grind on."""
    p = il.Params(m=0.44, c=1.17, k=0.59, g=0.17, r=1.0, omega=0.24)
    sol = il.simulate(p, t_end=20.0, t_record=0.0, x0=0.25, v0=0.9, max_impacts=20_000)
    assert sol.status == 1 and sol.n_impacts == 20_000
    assert sol.final[0] < 20.0
