"""Boundary curves in two parameters, against independent references: multipliers by
central differences of the simulator's n-period map at every point, the one-parameter
continuation at fixed values of the second parameter, a closed form of the flight written
here for the grazing curves, the closed-form amplitude of the non-impacting orbit, and the
regime map's classification either side of a period-doubling curve."""
import io
import math

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import minimize_scalar

import impactlib as il

from core_helpers import PAPER

P_SN = PAPER.replace(omega=2.0, g=0.5)       # a 2-impact period-1 orbit with a fold


def fd_map_multipliers(p, x, v, n, phase, m, h=1e-6):
    """Multipliers of the simulator's n-period map by central differences (step h:
    truncation ~h^2 |P'''| ~ 1e-10 here, rounding ~1e-16 / h ~ 1e-10).  Each run must
    keep the orbit's m impacts and end in flight, or the difference is not of one smooth
    branch of the map."""
    def f(x, v):
        sol = il.simulate(p, t_end=phase + n * p.T, t_record=phase, x0=x, v0=v, t0=phase)
        assert len(sol.impacts.t) == m and not sol.final[3], "the run left the orbit's branch"
        return np.array(sol.final[1:3])
    J = np.column_stack([(f(x + h, v) - f(x - h, v)) / (2 * h),
                         (f(x, v + h) - f(x, v - h)) / (2 * h)])
    return np.linalg.eigvals(J)


def flight(p, t0, x0, v0):
    """x(t) of free flight from (x0, v0) at t0, closed form for an underdamped oscillator:
    forced response A cos wt + B sin wt plus the damped homogeneous part."""
    assert p.c ** 2 < p.k * p.m
    a, w = p.c / p.m, p.omega
    beta = math.sqrt(p.k / p.m - a * a)
    den = (p.k - p.m * w * w) ** 2 + (2 * p.c * w) ** 2
    A, B = (p.k - p.m * w * w) / den, 2 * p.c * w / den
    h0 = x0 - (A * math.cos(w * t0) + B * math.sin(w * t0))
    hv0 = v0 - w * (-A * math.sin(w * t0) + B * math.cos(w * t0))

    def x(t):
        s = np.asarray(t, dtype=float) - t0
        hom = np.exp(-a * s) * (h0 * np.cos(beta * s) + (hv0 + a * h0) / beta * np.sin(beta * s))
        return hom + A * np.cos(w * t0 + w * s) + B * np.sin(w * t0 + w * s)
    return x


def interior_minima(x, t0, t1, samples=20001):
    """Every local minimum of x inside (t0, t1): dense samples, each refined by Brent."""
    ts = np.linspace(t0, t1, samples)
    xs = x(ts)
    out = []
    for i in np.flatnonzero((xs[1:-1] < xs[:-2]) & (xs[1:-1] <= xs[2:])) + 1:
        res = minimize_scalar(lambda t: float(x(t)), bounds=(ts[i - 1], ts[i + 1]),
                              method="bounded", options={"xatol": 1e-13})
        out.append((res.x, float(res.fun)))
    return out


def params_at(b, k):
    return b.params.replace(**{b.names[0]: b.values[k, 0], b.names[1]: b.values[k, 1]})


def branch_events(p, stop, kind, **kw):
    return [e for e in il.continuation(p, "omega", stop, **kw).events if e.kind == kind]


@pytest.fixture(scope="module")
def pd_upper():
    """The period-doubling of the 1-impact period-1 orbit near omega = 2.66, r = 0.8 -> 0."""
    e = branch_events(PAPER, 5.0, "period-doubling")[0]
    return il.boundary(e, "r", 0.0)


@pytest.fixture(scope="module")
def pd_lower():
    """The lower period-doubling near omega = 1.23, followed from r = 0.8 down: the curve
    turns in r near 0.636 and comes back up to r = 1 on the other period-doubling."""
    e = branch_events(PAPER, 0.5, "period-doubling")[0]
    return il.boundary(e, "r", 0.0)


@pytest.fixture(scope="module")
def sn_curve():
    e = branch_events(P_SN, 0.3, "saddle-node")[0]
    return il.boundary(e, "g", 0.0)


@pytest.fixture(scope="module")
def grazing_flight():
    e = branch_events(PAPER, 0.5, "grazing")[0]
    return il.boundary(e, "r", 0.2)


def test_period_doubling_curves_have_the_multiplier_minus_one_at_every_point(pd_upper,
                                                                            pd_lower):
    for b in (pd_upper, pd_lower):
        assert b.kind == "period-doubling" and b.names == ("omega", "r") and b.impacts == 1
        assert len(b.values) >= 100
        for k in range(len(b.values)):
            mu = fd_map_multipliers(params_at(b, k), b.x[k], b.v[k], b.n, b.phase, b.impacts)
            assert np.min(np.abs(mu + 1)) < 1e-6, (k, b.values[k], mu)


def test_lower_period_doubling_curve_passes_its_fold_and_ends_on_the_box_edge(pd_lower):
    r = pd_lower.values[:, 1]
    fold = [q for q in pd_lower.points if q.label == "fold in r"]
    assert len(fold) == 1 and r.min() == pytest.approx(fold[0].values[1], abs=1e-9)
    assert r[0] == 0.8 and r[-1] == 1.0 and "edge of the valid range of r" in pd_lower.message
    # the one-parameter continuation either side of the fold: two period-doublings of the
    # 1-impact orbit just above it, none just below
    r_fold, w_fold = fold[0].values[1], fold[0].values[0]
    above = branch_events(PAPER.replace(r=r_fold + 0.005), 0.5, "period-doubling")
    below = branch_events(PAPER.replace(r=r_fold - 0.005), 0.5, "period-doubling")
    assert len(above) == 2 and all(abs(e.value - w_fold) < 0.05 for e in above)
    assert below == []
    # where it ends (r = 1) the continuation at r = 1 has its other period-doubling
    at_one = branch_events(PAPER.replace(r=1.0), 0.5, "period-doubling")
    assert min(abs(e.value - pd_lower.values[-1, 0]) for e in at_one) < 1e-8


@pytest.mark.parametrize("r_fixed", [0.6, 0.3])
def test_curve_crosses_a_fixed_r_where_the_continuation_finds_the_event(r_fixed):
    e = branch_events(PAPER, 5.0, "period-doubling")[0]
    b = il.boundary(e, "r", r_fixed)
    assert b.values[-1, 1] == r_fixed and b.message == f"reached r = {r_fixed:g}"
    ref = branch_events(PAPER.replace(r=r_fixed), 5.0, "period-doubling")
    assert len(ref) == 1 and abs(ref[0].value - b.values[-1, 0]) < 1e-8


def test_both_crossings_of_the_bent_curve_at_r_07():
    starts = branch_events(PAPER, 0.5, "period-doubling")
    ends = sorted(il.boundary(e, "r", 0.7).values[-1, 0] for e in starts)
    ref = sorted(e.value for e in branch_events(PAPER.replace(r=0.7), 0.5, "period-doubling"))
    assert len(ref) == 2
    np.testing.assert_allclose(ends, ref, rtol=0, atol=1e-8)


def test_regime_map_is_period_1_and_period_2_either_side_of_the_curve(pd_upper):
    # the upper curve for r <= 0.3, away from the hysteresis of r = 0.8 near omega = 2.5-2.8
    rows = np.flatnonzero(pd_upper.values[:, 1] <= 0.3)
    for k in rows[[0, len(rows) // 2, -2]]:
        w, r = pd_upper.values[k]
        rm = il.regime_map(PAPER.replace(r=r), "omega", [w - 0.01, w + 0.01], "r", [r],
                           t_end=2000.0, t_record=1500.0)
        assert (rm.impacts[0, 0], rm.period[0, 0]) == (1, 1), rm.label(0, 0)
        assert rm.period[0, 1] == 2, rm.label(0, 1)


def test_saddle_node_curve_has_the_multiplier_plus_one_and_meets_grazing(sn_curve):
    b = sn_curve
    assert b.kind == "saddle-node" and b.impacts == 2 and len(b.values) > 50
    end = b.points[-1]
    assert end.label == "saddle-node meets grazing" and end.index == len(b.values) - 1
    # every point but the codimension-two end, where the map is not differentiable
    # (a flight touches the wall there)
    for k in range(len(b.values) - 1):
        mu = fd_map_multipliers(params_at(b, k), b.x[k], b.v[k], b.n, b.phase, b.impacts)
        assert np.min(np.abs(mu - 1)) < 1e-6, (k, b.values[k], mu)
    # at the end a flight of the orbit touches the wall (the closed form, dense)
    p = params_at(b, end.index)
    lows = []
    for j in range(2):
        t0 = b.impact_times[end.index, j]
        t1 = b.impact_times[end.index, 1] if j == 0 else b.impact_times[end.index, 0] + p.T
        x = flight(p, t0, p.g, -p.r * b.impact_velocities[end.index, j])
        lows += [xm - p.g for _, xm in interior_minima(x, t0, t1)]
    assert abs(min(lows)) < 1e-9


def test_saddle_node_curve_crosses_r_06_where_the_continuation_finds_it():
    e = branch_events(P_SN, 0.3, "saddle-node")[0]
    b = il.boundary(e, "r", 0.6)
    ref = branch_events(P_SN.replace(r=0.6), 0.3, "saddle-node", max_points=400)
    assert b.values[-1, 1] == 0.6
    assert len(ref) == 1 and abs(ref[0].value - b.values[-1, 0]) < 1e-8


def test_grazing_flight_touches_the_wall_at_every_point(grazing_flight):
    b = grazing_flight
    assert b.kind == "grazing" and b.condition == "flight 1 touches the wall"
    for k in range(len(b.values)):
        p = params_at(b, k)
        t0 = b.impact_times[k, 0]
        x = flight(p, t0, p.g, -p.r * b.impact_velocities[k, 0])
        lows = interior_minima(x, t0, t0 + p.T)
        t_low, x_low = min(lows, key=lambda q: q[1])
        assert abs(x_low - p.g) < 1e-9, (k, b.values[k], x_low - p.g)
        assert abs(t_low - b.touch_times[k]) < 1e-5
        # and arrives at the next impact with the orbit's own velocity
        assert abs(x(t0 + p.T) - p.g) < 1e-9


def test_grazing_curve_crosses_r_04_where_the_continuation_finds_it():
    e = branch_events(PAPER, 0.5, "grazing")[0]
    b = il.boundary(e, "r", 0.4)
    ref = branch_events(PAPER.replace(r=0.4), 0.5, "grazing")
    assert len(ref) == 1 and abs(ref[0].value - b.values[-1, 0]) < 1e-8


def test_zero_speed_grazing_follows_the_closed_form_amplitude():
    # c = 0.1, gap g = -0.3: the 1-impact orbit's impact speed reaches 0 at omega ~ 2.075,
    # where the non-impacting orbit's amplitude 1 / sqrt((k - m w^2)^2 + (2 c w)^2) is -g
    p = PAPER.replace(omega=2.0, c=0.1, g=-0.3)
    e = branch_events(p, 5.0, "grazing")[0]
    b = il.boundary(e, "g", -1.0)
    assert b.condition == "impact 1 at zero speed" and b.message == "reached g = -1"
    w, g = b.values[:, 0], b.values[:, 1]
    amplitude = 1 / np.sqrt((p.k - p.m * w ** 2) ** 2 + (2 * p.c * w) ** 2)
    np.testing.assert_allclose(g, -amplitude, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.impact_velocities[:, 0], 0.0, atol=1e-12)


def test_bad_input_names_every_field():
    e = branch_events(PAPER, 5.0, "period-doubling")[0]
    with pytest.raises(ValueError) as err:
        il.boundary(e, "omega", math.nan, ds=-1.0, max_points=1)
    msg = str(err.value)
    for field in ("name='omega' is the event's own parameter", "stop=nan", "ds=-1.0",
                  "max_points=1"):
        assert field in msg
    with pytest.raises(ValueError, match=r"event=\('grazing', 1.0\) carries no orbit"):
        il.boundary(il.Event("grazing", 1.0, PAPER, 0.0, 0.0, None, 0), "r", 0.5)
    with pytest.raises(ValueError, match=r"stop=1.5 is outside the valid range of r"):
        il.boundary(e, "r", 1.5)
    with pytest.raises(ValueError, match=r"event=3 is not an Event.*name='q' is not a parameter"):
        il.boundary(3, "q", 1.0)


def test_csv_holds_the_curve_and_its_header(pd_upper):
    text = pd_upper.to_csv()
    head = dict(line[2:].split(" = ", 1) for line in text.splitlines() if line.startswith("# "))
    assert head["kind"] == "period-doubling" and head["orbit"] == "1-impact period-1"
    assert (head["param_x"], head["param_y"]) == ("omega", "r")
    assert float(head["c"]) == PAPER.c and "omega" not in head and "r" not in head
    assert head["version"] == il.__version__
    df = pd.read_csv(io.StringIO(text), comment="#")
    np.testing.assert_array_equal(df["omega"], pd_upper.values[:, 0])
    np.testing.assert_array_equal(df["r"], pd_upper.values[:, 1])
    np.testing.assert_array_equal(df["mu1_re"], pd_upper.multipliers[:, 0].real)
    np.testing.assert_array_equal(df["u1"], pd_upper.impact_velocities[:, 0])


def test_contract_signature_result_fields_and_event_pickling(pd_upper):
    import dataclasses
    import inspect
    import pickle
    sig = inspect.signature(il.boundary)
    assert [(q.name, q.kind.name, q.default) for q in sig.parameters.values()] == [
        ("event", "POSITIONAL_OR_KEYWORD", inspect._empty),
        ("name", "POSITIONAL_OR_KEYWORD", inspect._empty),
        ("stop", "POSITIONAL_OR_KEYWORD", inspect._empty),
        ("ds", "KEYWORD_ONLY", None), ("max_points", "KEYWORD_ONLY", 2000)]
    names = {f.name for f in dataclasses.fields(il.Boundary)}
    assert {"kind", "names", "values", "x", "v", "multipliers", "impact_velocities",
            "points", "message"} <= names
    with pytest.raises(dataclasses.FrozenInstanceError):
        pd_upper.kind = "saddle-node"
    k = len(pd_upper.values)
    assert pd_upper.values.shape == (k, 2) and pd_upper.multipliers.shape == (k, 2)
    assert pd_upper.impact_velocities.shape == (k, 1) and pd_upper.x.shape == (k,)
    # an event keeps what boundary needs through pickling (the process pools use it)
    e = branch_events(PAPER, 5.0, "period-doubling")[0]
    e2 = pickle.loads(pickle.dumps(e))
    assert tuple(e2) == tuple(e) and (e2.name, e2.n, e2.phase) == ("omega", 1, 0.0)
    np.testing.assert_array_equal(e2.impact_times, e.impact_times)
    assert il.boundary(e2, "r", 0.6).values[-1, 0] == il.boundary(e, "r", 0.6).values[-1, 0]


def test_period_two_doubling_curve_meets_the_continuation_at_r_03():
    # period 2 -> 4 of the doubled branch at r = 0.6, followed to r = 0.3
    e = branch_events(PAPER.replace(r=0.6), 3.0, "period-doubling")[0]
    pd2 = branch_events(e.params, 3.0, "period-doubling", n=2, x0=e.x, v0=e.v)[0]
    b = il.boundary(pd2, "r", 0.3)
    assert b.n == 2 and b.impacts == 2 and b.values[-1, 1] == 0.3
    for k in np.linspace(0, len(b.values) - 1, 6).astype(int):
        mu = fd_map_multipliers(params_at(b, k), b.x[k], b.v[k], 2, b.phase, 2)
        assert np.min(np.abs(mu + 1)) < 1e-6, (k, b.values[k], mu)
    e3 = branch_events(PAPER.replace(r=0.3), 3.0, "period-doubling")[0]
    ref = branch_events(e3.params, 3.0, "period-doubling", n=2, x0=e3.x, v0=e3.v)
    assert abs(ref[0].value - b.values[-1, 0]) < 1e-8
