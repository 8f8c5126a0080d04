"""The comparison routes of bench/bench_speed.py are honest: the solve_ivp route finds the
same impacts as the exact method at the paper default, to the accuracy it is run at."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import impactlib as il

pytest.importorskip("scipy")
_spec = importlib.util.spec_from_file_location(
    "bench_speed", Path(__file__).resolve().parents[2] / "bench" / "bench_speed.py")
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)


def test_solve_ivp_route_matches_exact_at_paper_default():
    p = il.Params()
    ref = il.simulate(p, 200.0, t_record=100.0)
    times, status, _, restarts, _ = bench.ivp_run(p, 200.0, 100.0, method="DOP853",
                                                  rtol=1e-8, atol=1e-11)
    assert status == "ok"
    assert restarts >= len(ref.impacts)
    assert times.shape == ref.impacts.t.shape
    # DOP853 at rtol 1e-8 locates impacts to ~1e-9 (measured); 1e-7 leaves room
    np.testing.assert_allclose(times, ref.impacts.t, rtol=0, atol=1e-7)


def test_solve_ivp_route_sticks_instead_of_looping():
    # low forcing frequency: complete chattering, then sticking until the force turns
    p = il.Params(omega=0.3)
    times, status, _, _, _ = bench.ivp_run(p, 100.0, 0.0, budget=20.0)
    assert status == "ok"
    assert np.all(np.diff(times) >= 0)


def test_agreement_mask_counts_matching_values():
    p = il.Params()
    vals = np.array([1.0, 2.0, 3.0])
    a = il.bifurcation(p, "omega", vals, 100.0, 50.0)
    assert bench.agreement_mask(a, a).all()
    b = il.bifurcation(p, "omega", vals, 100.0, 50.0, method="rk4", dt=0.2)
    assert not bench.agreement_mask(a, b).all()
