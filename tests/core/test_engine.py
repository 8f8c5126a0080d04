"""The one event loop (impactlib.kernels.engine): callable from other jitted code, the same run
as simulate() for every method, and its carried tangent equal to central finite
differences of its own final state, with the determinant identity det J = r^(2 m)
exp(-2 c tau / m) (Müller 1995) over m impacts in a flight time tau."""
import math

import numpy as np
import pytest
from numba import njit

import impactlib as il
from impactlib.kernels import engine as E
from impactlib.kernels.flight import fastest_rate, system_constants
from impactlib.kernels.events import step_cap

from core_helpers import PAPER


@njit
def final_from_jitted_code(m, c, k, g, r, omega, t0, x0, v0, t_end, method, dt, tangent):
    """A jitted caller builds the inputs and reads the named outputs."""
    sp = system_constants(m, c, k, g, r, omega)
    ctl = E.controls(t_end, t0, step_cap(sp), fastest_rate(sp), dt, 1e-10, 1e-13, 1e6, 1e8,
                     method, tangent)
    res = np.empty(E.NRES)
    status = E.run_engine(sp, ctl, t0, x0, v0, E.no_buffers(), res)
    return status, res


@pytest.mark.parametrize("method, dt", [("exact", 0.0), ("rk4", 1e-3), ("rk45", 0.0)])
def test_engine_from_jitted_code_is_the_run_of_simulate(method, dt):
    p = PAPER.replace(omega=2.8)
    status, res = final_from_jitted_code(p.m, p.c, p.k, p.g, p.r, p.omega, 1.5, 0.3, -0.2,
                                         40.0, E.METHOD_IDS[method], dt, E.NO_TANGENT)
    kw = dict(dt=dt) if method == "rk4" else dict(rtol=1e-10, atol=1e-13)
    sol = il.simulate(p, t_end=40.0, t_record=1.5, t0=1.5, x0=0.3, v0=-0.2, method=method,
                      **({} if method == "exact" else kw))
    assert status == il.model.RunStatus.OK == sol.status
    # the same kernel on the same inputs: the same numbers to the bit
    assert (res[E.T_F], res[E.X_F], res[E.V_F], res[E.STUCK] != 0) == sol.final
    assert int(res[E.N_TOT]) == sol.n_impacts == len(sol.impacts)


CASES = {
    "underdamped": PAPER,
    "undamped": PAPER.replace(c=0.0, omega=2.5),
    "critical": il.Params(m=1.0, c=1.0, k=1.0, g=-0.4, r=0.8, omega=0.5),
    "overdamped": il.Params(m=1.0, c=3.0, k=1.0, g=-0.3, r=0.8, omega=0.5),
}


@pytest.mark.parametrize("name", CASES)
def test_carried_tangent_matches_finite_differences_and_the_determinant(name):
    """Two periods from a state in flight; central differences with h = 1e-6 have
    truncation error ~ h^2 |third derivative| ~ 1e-12 and rounding ~ eps / h ~ 1e-10
    times the size of the map's second derivative; 1e-6 relative leaves room for
    saltation factors of tens."""
    p = CASES[name]
    t0, t_end = 0.7, 0.7 + 2.0 * p.T
    x0, v0 = p.g + 0.5, 0.1

    def final(x, v, tangent=E.NO_TANGENT):
        st, res = final_from_jitted_code(p.m, p.c, p.k, p.g, p.r, p.omega, t0, x, v, t_end,
                                         E.EXACT, 0.0, tangent)
        assert st == 0 and res[E.STUCK] == 0
        return res

    res = final(x0, v0, E.JACOBIAN)
    J = res[E.J11:E.J22 + 1].reshape(2, 2)
    h = 1e-6
    fd = np.empty((2, 2))
    for j, (dx, dv) in enumerate(((h, 0.0), (0.0, h))):
        a, b = final(x0 + dx, v0 + dv), final(x0 - dx, v0 - dv)
        assert a[E.N_TOT] == b[E.N_TOT] == res[E.N_TOT]     # no impact gained or lost
        fd[:, j] = (a[E.X_F:E.V_F + 1] - b[E.X_F:E.V_F + 1]) / (2 * h)
    assert res[E.N_TOT] >= 1
    np.testing.assert_allclose(J, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
    m = res[E.N_TOT]
    det = p.r ** (2 * m) * math.exp(-2.0 * p.c / p.m * (t_end - t0))
    assert np.linalg.det(J) == pytest.approx(det, rel=1e-9)


def test_qr_marks_sum_to_the_log_determinant():
    """log|R11| + log|R22| over the marked window is log|det J| there: 2 m ln r - 2 c tau / m."""
    p = PAPER
    marks = np.linspace(100.0, 300.0, 5)
    logs = np.zeros((4, 2))
    imp_t, imp_v = np.empty(4096), np.empty(4096)
    sp = system_constants(p.m, p.c, p.k, p.g, p.r, p.omega)
    ctl = E.controls(300.0, 100.0, step_cap(sp), fastest_rate(sp), 0.0, 0.0, 0.0, 1e6, 1e8,
                     E.EXACT, E.QR_MARKS)
    res = np.empty(E.NRES)
    assert E.run_engine(sp, ctl, 0.0, 0.0, 0.0, E.buffers(imp_t=imp_t, imp_v=imp_v,
                                                          marks=marks, logs=logs), res) == 0
    m = int(res[E.N_MARKED])
    assert m == int(res[E.N_REC]) > 10
    want = 2 * m * math.log(p.r) - 2 * p.c / p.m * 200.0
    assert logs.sum() == pytest.approx(want, rel=1e-10)
