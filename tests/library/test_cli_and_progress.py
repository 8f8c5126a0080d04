"""The command line gives the Python API's numbers; long sweeps report monotone progress
ending at the total and stop within one chunk when cancelled."""
from __future__ import annotations

import subprocess
import sys
import threading

import numpy as np
import pytest

import impactlib as il
from impactlib.cli import main
from impactlib.io import read_csv

P = il.Params()


def _cli(tmp_path, *args, name="out.csv"):
    out = tmp_path / name
    assert main([*args, "--out", str(out)]) == 0
    return out


def test_simulate_command_is_simulate(tmp_path):
    out = _cli(tmp_path, "simulate", "--omega", "2.8", "--t-end", "300", "--t-record", "200",
               "--table", "poincare")
    settings, cols = read_csv(out)
    sol = il.simulate(P.replace(omega=2.8), t_end=300, t_record=200)
    assert np.array_equal(cols["x"], sol.poincare.x) and np.array_equal(cols["v"], sol.poincare.v)
    assert settings["omega"] == "2.8" and settings["t_record"] == "200.0"


def test_bifurcation_command_is_bifurcation(tmp_path):
    out = _cli(tmp_path, "bifurcation", "--name", "r", "--start", "0.2", "--stop", "0.9",
               "--num", "30", "--omega", "2.7", "--t-end", "200", "--t-record", "100")
    _, cols = read_csv(out)
    bif = il.bifurcation(P.replace(omega=2.7), "r", np.linspace(0.2, 0.9, 30), t_end=200,
                         t_record=100)
    assert np.array_equal(cols["r"], bif.param) and np.array_equal(cols["v"], bif.v)
    assert np.array_equal(cols["t"], bif.t)


def test_regime_map_and_basins_commands_as_netcdf(tmp_path):
    xr = pytest.importorskip("xarray")
    out = _cli(tmp_path, "regime-map", "--nx", "6", "--ny", "4", "--t-end", "150",
               "--t-record", "100", name="map.nc")
    rm = il.regime_map(P, "omega", np.linspace(0.1, 5, 6), "r", np.linspace(0, 1, 4),
                       t_end=150, t_record=100)
    ds = xr.load_dataset(out)
    assert ds.identical(rm.to_xarray())
    out = _cli(tmp_path, "basins", "--omega", "2.62", "--n", "12", "8", name="basins.nc")
    b = il.basins(P.replace(omega=2.62), (0, 1), (-1.5, 1.5), n=(12, 8))
    assert np.array_equal(xr.load_dataset(out)["attractor"].values, b.labels)


def test_orbit_command_is_periodic_orbit(tmp_path):
    out = _cli(tmp_path, "orbit", "--omega", "2.5")
    settings, cols = read_csv(out)
    o = il.periodic_orbit(P.replace(omega=2.5))
    assert float(settings["x"]) == o.x and np.array_equal(cols["v"], o.impact_velocities)


def test_bad_value_is_one_line_and_exit_2():
    run = subprocess.run([sys.executable, "-m", "impactlib", "simulate", "--t-end", "-5"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert run.stderr.strip() == "impactlib simulate: invalid run: t_end=-5.0 must be > 0"


def test_accuracy_out_is_required():
    run = subprocess.run([sys.executable, "-m", "impactlib", "accuracy", "--quick"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "--out" in run.stderr


def _recorder():
    calls = []
    return calls, (lambda done, total: calls.append((done, total)))


def test_progress_counts_are_monotone_and_end_at_the_total():
    values = np.linspace(1.0, 3.0, 150)
    calls, cb = _recorder()
    bif = il.bifurcation(P, "omega", values, t_end=100, t_record=50, progress=cb)
    done = [d for d, _ in calls]
    assert done == sorted(done) and done[-1] == 150 and {t for _, t in calls} == {150}
    assert len(calls) == 3                        # chunks of 64
    assert bif == il.bifurcation(P, "omega", values, t_end=100, t_record=50)
    calls, cb = _recorder()
    vy = np.linspace(0.2, 0.9, 5)
    rm = il.regime_map(P, "omega", values[:7], "r", vy, t_end=100, t_record=50, progress=cb)
    assert [d for d, _ in calls] == [2, 4, 5]
    assert rm == il.regime_map(P, "omega", values[:7], "r", vy, t_end=100, t_record=50)
    calls, cb = _recorder()
    b = il.basins(P.replace(omega=2.62), (0, 1), (-1.5, 1.5), n=(10, 9), progress=cb)
    done = [d for d, _ in calls]
    assert done == sorted(done) and done[-1] == 9
    assert b == il.basins(P.replace(omega=2.62), (0, 1), (-1.5, 1.5), n=(10, 9))


def test_iter_regime_map_pieces_make_the_map():
    vx, vy = np.linspace(1.0, 3.0, 5), np.linspace(0.3, 0.9, 5)
    parts = list(il.iter_regime_map(P, "omega", vx, "r", vy, t_end=100, t_record=50, rows=2))
    assert [p.values_y.size for p in parts] == [2, 2, 1]
    from impactlib.sweeps.diagrams import merge_regime_maps
    assert merge_regime_maps(parts) == il.regime_map(P, "omega", vx, "r", vy, t_end=100,
                                                     t_record=50)


def test_iter_regime_map_sizes_blocks_by_a_callable():
    vx, vy = np.linspace(1.0, 3.0, 4), np.linspace(0.3, 0.9, 7)
    asked = []

    def rows(done, elapsed):
        asked.append((done, elapsed))
        return 1 if done == 0 else 4               # a small first block, then larger
    parts = list(il.iter_regime_map(P, "omega", vx, "r", vy, t_end=100, t_record=50,
                                    rows=rows))
    assert [p.values_y.size for p in parts] == [1, 4, 2]
    assert [d for d, _ in asked] == [0, 1, 5]
    assert all(b >= a >= 0 for (_, a), (_, b) in zip(asked, asked[1:]))
    from impactlib.sweeps.diagrams import merge_regime_maps
    assert merge_regime_maps(parts) == il.regime_map(P, "omega", vx, "r", vy, t_end=100,
                                                     t_record=50)
    with pytest.raises(ValueError, match="rows=0"):
        next(il.iter_regime_map(P, "omega", vx, "r", vy, rows=0))


def test_cancel_stops_within_one_chunk():
    values = np.linspace(1.0, 3.0, 64 * 6)
    cancel = threading.Event()
    calls = []

    def cb(done, total):
        calls.append(done)
        cancel.set()                               # ask to stop after the first chunk

    bif = il.bifurcation(P, "omega", values, t_end=100, t_record=50, progress=cb, cancel=cancel)
    assert calls == [64] and bif.values.size == 64
    assert bif == il.bifurcation(P, "omega", values[:64], t_end=100, t_record=50)
    cancel.clear()
    rows = []
    b = il.basins(P.replace(omega=2.62), (0, 1), (-1.5, 1.5), n=(20, 40),
                  progress=lambda d, t: (rows.append(d), cancel.set()), cancel=cancel)
    assert len(rows) == 1 and not b.complete and "cancelled" in b.message
    assert np.all(b.labels[rows[0]:] == -1) and np.all(b.labels[:rows[0]] >= -1)


def test_progress_rejects_a_non_callable():
    with pytest.raises(ValueError, match="progress='yes' must be True, False, None or a callable"):
        il.bifurcation(P, "omega", [1.0, 2.0], progress="yes")
