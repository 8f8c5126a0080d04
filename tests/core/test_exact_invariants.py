"""Invariants of the exact method over a box of valid parameters (hypothesis)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import impactlib as il
from impactlib.verify.report import steady_orbit

from core_helpers import EPS

T_END = 60.0


@settings(max_examples=60, deadline=None, derandomize=True)
@given(m=st.floats(0.1, 10.0), c=st.floats(0.0, 2.0), k=st.floats(0.0, 10.0),
       g=st.floats(-0.5, 0.5), r=st.floats(0.0, 1.0), omega=st.floats(0.1, 5.0),
       v0=st.floats(-1.0, 1.0))
def test_exact_run_invariants(m, c, k, g, r, omega, v0):
    p = il.Params(m=m, c=c, k=k, g=g, r=r, omega=omega)
    sol = il.simulate(p, t_end=T_END, t_record=0.0, x0=max(0.0, g), v0=v0, dense=600)
    assert sol.status in (0, 1, 2)
    imp = sol.impacts
    # impacts: ordered in time, velocity before impact <= 0, phase = t mod T
    assert np.all(np.diff(imp.t) >= 0)
    assert np.all(imp.v <= 0)
    assert np.all((imp.phase >= 0) & (imp.phase < p.T))
    # never behind the wall (to rounding of the largest term of x = h + x_p)
    scale = steady_orbit(p)[2] + abs(g) + abs(v0) / max(p.omega_n, 1e-3) + 1.0
    assert np.all(sol.dense.x >= g - 64 * EPS * scale)
    # sticking intervals: ordered, disjoint, inside the run, with no impact strictly inside,
    # and only where the net force does not push the mass off the wall
    s = sol.sticking
    assert np.all(s[:, 1] >= s[:, 0])
    assert np.all(s[1:, 0] >= s[:-1, 1])
    assert np.all((s >= 0) & (s <= T_END))
    for a, b in s:
        assert not np.any((imp.t > a) & (imp.t < b))
        mid = 0.5 * (a + b)
        if b > a:
            assert np.cos(omega * mid) - k * g <= 1e-12
    # at rest on the wall only where the dense output says so
    on_wall = np.zeros(sol.dense.t.shape, dtype=bool)
    for a, b in s:
        on_wall |= (sol.dense.t > a) & (sol.dense.t < b)
    assert np.all(sol.dense.x[on_wall] == g) and np.all(sol.dense.v[on_wall] == 0)
