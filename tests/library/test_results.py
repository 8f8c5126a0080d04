"""Results in the tools researchers use: bounded reprs naming label and status, HTML,
data equality, tidy DataFrames against the result's own arrays, CSV with the settings
block read back, xarray through netCDF and back."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import impactlib as il
from impactlib.io import read_csv, read_header

P = il.Params()


@pytest.fixture(scope="module")
def results():
    omegas = np.linspace(0.5, 4.5, 300)
    return {
        # big ones: a long run, a wide sweep, a large grid
        "solution": il.simulate(P, t_end=20000.0, t_record=100.0, dense=5000),
        "bifurcation": il.bifurcation(P, "omega", omegas, t_end=200.0, t_record=100.0),
        "lyap_bif": il.bifurcation(P, "omega", omegas[::20], t_end=200.0, t_record=100.0,
                                   lyapunov=True),
        "regime_map": il.regime_map(P, "omega", np.linspace(0.5, 4.5, 40), "r",
                                    np.linspace(0.1, 0.9, 30), t_end=150.0, t_record=100.0),
        "basins": il.basins(P.replace(omega=2.62), (0, 1), (-1.5, 1.5), n=(40, 30)),
        "orbit": il.periodic_orbit(P),
        "branch": il.continuation(P, "omega", 2.8),
        "lyapunov": il.lyapunov(P, t_end=600.0, t_record=100.0),
    }


NAMES = ["solution", "bifurcation", "lyap_bif", "regime_map", "basins", "orbit", "branch",
         "lyapunov"]


@pytest.mark.parametrize("name", NAMES)
def test_repr_is_short_and_names_the_outcome(results, name):
    r = results[name]
    text = repr(r)
    assert len(text) < 1000, (len(text), text)
    assert 3 <= text.count("\n") + 1 <= 10
    outcome = {"solution": "status 0", "bifurcation": "every run reached t_end",
               "lyap_bif": "every run reached t_end", "regime_map": "1-impact period-1",
               "basins": "1-impact period-1", "orbit": "1-impact period-1",
               "branch": "period-doubling", "lyapunov": "λ1 = -0.11"}[name]
    assert outcome in text, text
    html = r._repr_html_()
    assert html.startswith("<table>") and html.count("<tr>") == text.count("\n")
    assert "<script" not in html


def test_equality_compares_data_not_identity_or_timing(results):
    sol = results["solution"]
    again = il.simulate(P, t_end=20000.0, t_record=100.0, dense=5000)
    assert again is not sol and again.elapsed != sol.elapsed
    assert again == sol
    assert il.simulate(P, t_end=20000.0, t_record=100.0, dense=5000, v0=1e-9) != sol
    bif = results["bifurcation"]
    assert il.bifurcation(P, "omega", bif.values, t_end=200.0, t_record=100.0) == bif
    assert il.bifurcation(P, "omega", bif.values, t_end=201.0, t_record=100.0) != bif
    # NaN entries (Lyapunov strip) compare equal to themselves
    lb = results["lyap_bif"]
    assert lb == il.bifurcation(P, "omega", lb.values, t_end=200.0, t_record=100.0, lyapunov=True)


def test_solution_dataframe_is_one_row_per_impact(results):
    sol = results["solution"]
    df = sol.to_dataframe()
    assert len(df) == len(sol.impacts)
    assert np.array_equal(df["t"], sol.impacts.t) and np.array_equal(df["v"], sol.impacts.v)
    assert (df["omega"] == P.omega).all() and (df["method"] == "exact").all()
    dense = sol.to_dataframe("dense")
    assert len(dense) == 5000 and np.array_equal(dense["x"], sol.dense.x)
    with pytest.raises(ValueError, match="table='nope'.*'impacts', 'poincare'"):
        sol.to_dataframe("nope")


def test_bifurcation_dataframes(results):
    bif = results["bifurcation"]
    df = bif.to_dataframe()
    assert len(df) == len(bif) and np.array_equal(df["omega"], bif.param)
    assert np.array_equal(df["index"], bif.index)
    # every impact row's value is the swept value it indexes
    assert np.array_equal(df["omega"].to_numpy(), bif.values[df["index"].to_numpy()])
    per = bif.to_dataframe("values")
    assert len(per) == bif.values.size
    assert per["n_impacts"].sum() >= len(bif)
    assert set(per.columns) >= {"omega", "status", "n_impacts", "m", "c", "k", "g", "r", "t_end"}


def test_regime_map_dataframe_labels_match_label(results):
    rm = results["regime_map"]
    df = rm.to_dataframe()
    ny, nx = rm.impacts.shape
    assert len(df) == nx * ny
    for i in (0, 17, nx * ny - 1):
        iy, ix = divmod(i, nx)
        row = df.iloc[i]
        assert row["omega"] == rm.values_x[ix] and row["r"] == rm.values_y[iy]
        assert row["label"] == rm.label(iy, ix)
        assert row["m"] == rm.impacts[iy, ix] and row["n"] == rm.period[iy, ix]


def test_basins_dataframe(results):
    b = results["basins"]
    df = b.to_dataframe()
    assert len(df) == b.labels.size
    fractions = df["attractor"].value_counts(normalize=True).sort_index()
    assert np.allclose(fractions.loc[range(len(b.attractors))].to_numpy(), b.fractions)
    assert set(df["label"]) <= {a.label for a in b.attractors} | {"undecided"}


def test_orbit_branch_lyapunov_dataframes(results):
    o, br, ly = results["orbit"], results["branch"], results["lyapunov"]
    assert len(o.to_dataframe()) == len(o.impact_times)
    df = br.to_dataframe()
    assert len(df) == br.param.size
    assert np.allclose(np.hypot(df["mu1_real"], df["mu1_imag"]), np.abs(br.multipliers[:, 0]))
    assert list(ly.to_dataframe()["exponent"]) == list(ly.exponents)


@pytest.mark.parametrize("name,table", [("solution", "impacts"), ("solution", "poincare"),
                                        ("bifurcation", "impacts"), ("bifurcation", "values"),
                                        ("regime_map", None), ("basins", None), ("orbit", None),
                                        ("branch", None), ("lyapunov", None)])
def test_csv_round_trip_with_settings(results, name, table, tmp_path):
    r = results[name]
    path = tmp_path / "out.csv"
    r.to_csv(path, table)
    settings, cols = read_csv(path)
    want = {k: v for k, v in r.settings().items()}
    for key, value in want.items():
        got = settings[key]
        if isinstance(value, float):
            assert float(got) == value or (math.isnan(value) and got == "nan"), key
        elif isinstance(value, complex):
            assert complex(got) == value, key
        elif value is None:
            assert got == "", key
        else:
            assert got == str(value), key
    assert settings["version"] == il.__version__
    frame = r.to_dataframe(table)
    for col, arr in cols.items():
        # every number exactly (shortest repr reads back bit for bit)
        assert np.array_equal(arr, frame[col].to_numpy(dtype=float), equal_nan=True), col
    # pandas reads the same file with comment="#"
    df = pd.read_csv(path, comment="#")
    assert list(df.columns) == list(cols) and len(df) == len(frame)
    assert read_header(path.read_text()) == settings


def test_solution_header_names_the_start(tmp_path):
    sol = il.simulate(P, t_end=50.0, x0=0.5, v0=-0.25, method="rk4", dt=0.01)
    sol.to_csv(tmp_path / "s.csv")
    h = read_header(tmp_path / "s.csv")
    assert (h["x0"], h["v0"], h["dt"], h["method"]) == ("0.5", "-0.25", "0.01", "rk4")
    assert "rtol" not in h


@pytest.mark.parametrize("name", ["bifurcation", "lyap_bif", "regime_map", "basins", "branch"])
def test_xarray_round_trips_through_netcdf(results, name, tmp_path):
    xr = pytest.importorskip("xarray")
    ds = results[name].to_xarray()
    path = tmp_path / "out.nc"
    ds.to_netcdf(path)
    back = xr.load_dataset(path)
    assert back.identical(ds), (back, ds)


def test_xarray_dims_and_coordinates(results):
    pytest.importorskip("xarray")
    rm = results["regime_map"].to_xarray()
    assert rm["m"].dims == ("r", "omega")
    assert np.array_equal(rm["omega"], results["regime_map"].values_x)
    assert rm.attrs["t_end"] == 150.0 and rm.attrs["method"] == "exact"
    # a cell read by coordinates is the cell of the arrays
    rmap = results["regime_map"]
    assert int(rm["m"].sel(omega=rmap.values_x[3], r=rmap.values_y[5])) == rmap.impacts[5, 3]
    bif = results["bifurcation"].to_xarray()
    assert bif["status"].dims == ("omega",) and bif["v"].dims == ("impact",)
    b = results["basins"].to_xarray()
    assert list(b["attractor_label"].values) == [a.label for a in results["basins"].attractors]


def test_solution_fields_are_all_documented():
    import dataclasses

    for cls in (il.Solution, il.Bifurcation, il.RegimeMap, il.Basins, il.PeriodicOrbit,
                il.Branch, il.Lyapunov):
        doc = cls.__doc__
        missing = [f.name for f in dataclasses.fields(cls) if f.name not in doc]
        assert not missing, (cls.__name__, missing)


def test_bad_run_names_only_the_fields_given():
    with pytest.raises(ValueError) as err:
        il.simulate(P, t_end=-5)
    assert "t_end=-5.0 must be > 0" in str(err.value) and "t_record" not in str(err.value)
    with pytest.raises(ValueError, match=r"t_record=-1.0 must be >= 0"):
        il.simulate(P, t_end=-5, t_record=-1)
    with pytest.raises(ValueError, match=r"t_record=600.0 must lie in \[0, t_end=500.0\]"):
        il.simulate(P, t_end=500, t_record=600)
