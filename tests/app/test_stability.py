"""The stability readout, strip and branch overlay of a session, without a browser.

References are independent of the app and of impactlib's orbit code: the period-1 orbit
is solved here by scipy.optimize.root on the closed-form flight, its multipliers by
central differences of a closed-form one-period map (impact time by brentq); the
Lyapunov sum rule is an exact identity."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq, root

import impactlib as il
from app import stability, state

# -- closed-form flight of the paper's oscillator (underdamped), written here ------------


def flight(p, t1, x1, v1, t):
    """State at t of the free flight from (x1, v1) at t1: homogeneous + particular."""
    a = p.c / p.m
    wd = math.sqrt(p.k / p.m - a * a)
    det = p.k - p.m * p.omega ** 2
    d = det ** 2 + (2 * p.c * p.omega) ** 2
    P, Q = det / d, 2 * p.c * p.omega / d

    def xp(s):
        return P * math.cos(p.omega * s) + Q * math.sin(p.omega * s)

    def vp(s):
        return p.omega * (Q * math.cos(p.omega * s) - P * math.sin(p.omega * s))
    A = x1 - xp(t1)
    B = (v1 - vp(t1) + a * A) / wd
    s = t - t1
    e = math.exp(-a * s)
    x = e * (A * math.cos(wd * s) + B * math.sin(wd * s)) + xp(t)
    v = e * ((-a * A + wd * B) * math.cos(wd * s) + (-a * B - wd * A) * math.sin(wd * s)) + vp(t)
    return x, v


def period_one_orbit(p, guess):
    """(t1, u): impact time in [0, T) and impact velocity of a 1-impact period-1 orbit:
    the flight from (g, -r u) at t1 is back at (g, u) at t1 + T."""
    def residual(z):
        x, v = flight(p, z[0], p.g, -p.r * z[1], z[0] + p.T)
        return [x - p.g, v - z[1]]
    sol = root(residual, guess, method="hybr", options={"xtol": 1e-14})
    assert max(map(abs, residual(sol.x))) < 1e-12
    return sol.x[0] % p.T, sol.x[1]


def one_period_map(p, x, v, t_impact_guess):
    """The stroboscopic map from (x, v) at t = 0 to t = T with one impact, near the
    orbit: the impact time by brentq on x(t) = g around the guess, then the reset."""
    f = lambda t: flight(p, 0.0, x, v, t)[0] - p.g  # noqa: E731
    ti = brentq(f, t_impact_guess - 0.05, t_impact_guess + 0.05, xtol=1e-15)
    _, vi = flight(p, 0.0, x, v, ti)
    return np.array(flight(p, ti, p.g, -p.r * vi, p.T))


def test_paper_defaults_readout_is_the_closed_form_period_one_orbit(make_explorer):
    e = make_explorer()
    r = e.readout
    assert r.kind == "orbit" and r.verdict == "stable"
    p = il.Params()
    t1, u = period_one_orbit(p, [2.0, -0.5])
    x, v = flight(p, t1, p.g, -p.r * u, p.T)            # on the section t = T ≡ 0
    orb = r.orbit
    assert orb.label == "1-impact period-1" and orb.n == 1 and orb.impacts == 1
    assert abs(orb.x - x) < 1e-9 and abs(orb.v - v) < 1e-9
    h = 1e-6
    J = np.empty((2, 2))
    for j in range(2):
        dz = np.zeros(2)
        dz[j] = h
        J[:, j] = (one_period_map(p, *(np.array([x, v]) + dz), t1)
                   - one_period_map(p, *(np.array([x, v]) - dz), t1)) / (2 * h)
    ref = np.sort(np.abs(np.linalg.eigvals(J)))[::-1]
    assert np.allclose(np.abs(orb.multipliers), ref, atol=1e-6)
    assert abs(ref[0] - 0.69) < 0.01 and abs(ref[1] - 0.68) < 0.01     # the figures
    assert np.all(np.abs(np.imag(orb.multipliers)) < 1e-12)
    text = e.controls.stability.object
    for frag in ("1-impact period-1", f"{ref[0]:.4f}", f"{ref[1]:.4f}", "stable"):
        assert frag in text, (frag, text)


def test_sticking_is_said_plainly(make_explorer):
    e = make_explorer(omega="0.2")
    r = e.readout
    assert r.sticks
    text = e.controls.stability.object
    assert "sticks to the wall" in text
    if r.kind == "orbit":
        assert np.all(r.orbit.multipliers == 0) and "multipliers 0" in text
    else:
        assert np.all(r.lyapunov.exponents == -math.inf) and "−∞" in text


def test_non_periodic_motion_shows_exponents_with_the_sum_rule(make_explorer):
    e = make_explorer(omega="2.8")
    r = e.readout
    assert r.kind == "exponents" and r.orbit is None
    ly = r.lyapunov
    p = il.Params(omega=2.8)
    tau = ly.window[1] - ly.window[0]
    # exact identity: lambda1 + lambda2 = -2c/m + 2 nu ln r, nu impacts per unit time
    nu = ly.n_impacts / tau
    assert abs(ly.exponents.sum() - (-2 * p.c / p.m + 2 * nu * math.log(p.r))) < 1e-8
    # the label is earned: chaotic only when lambda1 exceeds twice its error
    assert ("chaotic" in r.verdict) == bool(ly.exponents[0] > 2 * ly.error[0])
    text = e.controls.stability.object
    assert "λ1" in text and "±" in text


def test_readout_is_shared_between_sessions_and_ignores_the_method(make_explorer):
    a = make_explorer(omega="2.62")
    b = make_explorer(omega="2.62", method="rk4")
    assert a.readout is b.readout
    assert stability.readout_key(a._wanted) == stability.readout_key(b._wanted)


def test_bad_settings_keep_the_last_readout(make_explorer):
    e = make_explorer()
    before = e.readout
    e.settings.r = 1.5
    assert "r" in e.message and e.readout is before


@pytest.mark.parametrize("x,n", [(np.array([1.0, 2.0] * 5), 2), (np.arange(10.0), 0)])
def test_repeat_period(x, n):
    assert stability.repeat_period(x, x) == n


def test_strip_is_aligned_with_the_diagram_and_shares_its_x_axis(make_explorer):
    e = make_explorer(bif_min="1", bif_max="3", bif_n="41")
    strip = e.lyapunov.source.data
    values = np.linspace(1.0, 3.0, 41)
    assert np.array_equal(strip["omega"], values)            # one row per swept value
    assert set(np.unique(e.bifurcation.source.data["omega"])) <= set(values)
    assert e.lyapunov.figure.x_range is e.bifurcation.figure.x_range
    # at omega = 2 the strip's exponent is ln|mu1| / T of the closed-form orbit; the
    # diagram's window is 250 time units, where the two close multipliers (0.690, 0.677)
    # leave a finite-window bias of a few 1e-4 (the core's 1e-3 test uses 4500)
    p = il.Params()
    t1, u = period_one_orbit(p, [2.0, -0.5])
    x, v = flight(p, t1, p.g, -p.r * u, p.T)
    h = 1e-6
    J = np.column_stack([(one_period_map(p, x + h * (j == 0), v + h * (j == 1), t1)
                          - one_period_map(p, x - h * (j == 0), v - h * (j == 1), t1)) / (2 * h)
                         for j in range(2)])
    mu1 = np.max(np.abs(np.linalg.eigvals(J)))
    lam = np.asarray(strip["lyapunov"])
    assert abs(lam[20] - math.log(mu1) / p.T) < 2e-3
    # the chaos band of Fig. 6 (omega = 2.8, independently chaotic by the readout test)
    assert lam[np.argmin(np.abs(values - 2.8))] > 0


def test_strip_draws_sticking_and_undefined_values_at_the_bottom(make_explorer):
    e = make_explorer(bif_min="0.1", bif_max="0.6", bif_n="12")
    d = e.lyapunov.source.data
    lam, y = np.asarray(d["lyapunov"]), np.asarray(d["y"])
    sticks = lam == -np.inf
    assert sticks.any() and len(lam) == 12                     # nothing dropped
    lo, hi = e.lyapunov.figure.y_range.start, e.lyapunov.figure.y_range.end
    assert np.all((y[sticks] > lo) & (y[sticks] < lo + 0.1 * (hi - lo)))
    assert {d["marker"][i] for i in np.flatnonzero(sticks)} == {"inverted_triangle"}
    assert np.all(y[np.isfinite(lam)] == lam[np.isfinite(lam)])
    assert f"{int(sticks.sum())} stick (−∞" in e.lyapunov.figure.title.text


def multiplier_min(p, guess):
    """The most negative eigenvalue of the closed-form one-period map's Jacobian at the
    period-1 orbit (central differences, h = 1e-6)."""
    t1, u = period_one_orbit(p, guess)
    x, v = flight(p, t1, p.g, -p.r * u, p.T)
    h = 1e-6
    J = np.column_stack([(one_period_map(p, x + h * (j == 0), v + h * (j == 1), t1)
                          - one_period_map(p, x - h * (j == 0), v - h * (j == 1), t1)) / (2 * h)
                         for j in range(2)])
    return np.min(np.real(np.linalg.eigvals(J))), u


def test_branches_from_the_url_locate_the_period_doubling_of_fig3d(make_explorer):
    e = make_explorer(r="0.6", branches="1", bif_min="1.5", bif_max="3.5", bif_n="40")
    assert e.settings.branches is True and e.run.branches is True
    from app import state
    assert state.to_query(e.run)["branches"] == "1"
    b = e.branches
    assert len(b.stable.data["xs"]) > 0 and len(b.unstable.data["xs"]) > 0
    assert len(b.events.data["x"]) > 0 and all(r.visible for r in b.renderers)
    # the period-1 branch loses stability where a closed-form multiplier crosses -1
    p = il.Params(r=0.6)
    lo, hi = 2.66, 2.68
    assert multiplier_min(p.replace(omega=lo), [2.0, -0.5])[0] > -1
    assert multiplier_min(p.replace(omega=hi), [2.0, -0.5])[0] < -1
    pd = [x for x, t in zip(b.events.data["x"], b.events.data["text"]) if t.startswith("PD")]
    assert any(lo < x < hi for x in pd), pd
    # the stable line through omega = 2 is the closed-form orbit's impact velocity (to the
    # linear interpolation between continuation points, a few 1e-4 at these steps)
    _, u = multiplier_min(p.replace(omega=2.0), [2.0, -0.5])
    at2 = []
    for xs, ys in zip(b.stable.data["xs"], b.stable.data["ys"]):
        if np.all(np.diff(xs) < 0):
            xs, ys = xs[::-1], ys[::-1]
        if min(xs) <= 2.0 <= max(xs) and np.all(np.diff(xs) > 0):
            at2.append(np.interp(2.0, xs, ys))
    assert any(abs(y - u) < 2e-3 for y in at2), (at2, u)


def test_branch_overlay_is_built_on_request_and_switched_off(make_explorer):
    e = make_explorer()
    names = {r.name for r in e.bifurcation.figure.renderers}
    assert not names & {"branches_stable", "branches_unstable", "branch_events"}
    e.settings.branches = True
    assert e.diagram.job.done.wait(60) and e.diagram.branch_job.done.wait(120)
    names = {r.name for r in e.bifurcation.figure.renderers}
    assert {"branches_stable", "branches_unstable", "branch_events"} <= names
    shown = e.branches.stable.data["xs"]
    assert len(shown) > 0
    e.settings.branches = False
    assert not any(r.visible for r in e.branches.renderers)
    assert len(e.branches.stable.data["xs"]) == 0
    e.settings.branches = True                   # from the cache: the same lines at once
    assert len(e.branches.stable.data["xs"]) == len(shown)


def test_branch_flag_in_the_url_must_be_on_or_off(make_explorer):
    e = make_explorer(branches="maybe")
    assert "branches" in e.message and e.settings.branches is False


def test_a_slowly_settling_period_one_orbit_is_not_called_period_two(make_explorer):
    """At omega = 1.25 (r = 0.8), just above a period doubling at about 1.23, the
    multiplier near -1 makes the motion settle slowly; the readout must name the
    period-1 orbit, the stable fixed point of the closed-form one-period map."""
    e = make_explorer(omega="1.25")
    p = il.Params(omega=1.25)
    found = []
    for t_guess in np.linspace(0.0, p.T, 8, endpoint=False):
        try:
            t1, u = period_one_orbit(p, [t_guess, -1.4])
        except AssertionError:
            continue
        x, v = flight(p, t1, p.g, -p.r * u, p.T)
        h = 1e-6
        J = np.column_stack([(one_period_map(p, x + h * (j == 0), v + h * (j == 1), t1)
                              - one_period_map(p, x - h * (j == 0), v - h * (j == 1), t1))
                             / (2 * h) for j in range(2)])
        if u < 0 and np.max(np.abs(np.linalg.eigvals(J))) < 1:
            found.append((x, v))
    assert found, "no stable closed-form period-1 orbit"
    orb = e.readout.orbit
    assert orb is not None and orb.label == "1-impact period-1" and orb.stable
    assert min(max(abs(orb.x - x), abs(orb.v - v)) for x, v in found) < 1e-8


def test_strip_of_an_up_and_down_sweep_has_both_chains(make_explorer):
    e = make_explorer(bif_sweep="both", bif_min="2.4", bif_max="3.0", bif_n="13")
    d = e.lyapunov.source.data
    values = np.linspace(2.4, 3.0, 13)
    assert np.array_equal(np.asarray(d["omega"]), np.repeat(values, 2))
    assert list(d["sweep"]) == [1, -1] * 13                     # up before down, per value
    finite = np.isfinite(np.asarray(d["lyapunov"]))
    assert {c for c, f, s in zip(d["color"], finite, d["sweep"]) if f and s == 1} <= {"#1f5fa8"}
    assert {c for c, f, s in zip(d["color"], finite, d["sweep"]) if f and s == -1} <= {"#e08214"}


def test_readout_of_a_sticking_motion_never_speaks_of_an_error_it_has_not():
    """ω = 0.05: the window holds fewer than 4 periods and the motion sticks (λ = −∞):
    the verdict says both, not "λ₁ within twice its error"."""
    run = state.validate({**state.defaults(), "omega": 0.05})
    r = stability.readout(run)
    assert r.kind == "exponents" and r.lyapunov.sticks
    assert "twice its error" not in r.verdict
    assert "fewer than 4 periods" in r.verdict or "shorter than 4 periods" in r.verdict
    assert "−∞" in r.verdict


@pytest.mark.parametrize("kind,label,lam,unbounded,message,expect", [
    ("unbounded", "unbounded (no dissipation): the impact speed grows every cycle",
     math.nan, True, "", "unbounded (no dissipation)"),
    ("chaotic", "chaotic (∞-impact period-∞)", 0.2, False, "", "chaotic: λ₁ is positive"),
    ("undetermined", "undetermined (no Lyapunov exponent: stopped)", math.nan, False,
     "stopped at max_impacts", "no exponents: stopped at max_impacts"),
])
def test_readout_verdict_for_every_status(kind, label, lam, unbounded, message, expect):
    from types import SimpleNamespace

    from impactlib.analysis.classify import Motion
    motion = Motion(math.nan, math.nan, kind, label,
                    lam if kind == "chaotic" else math.nan, 0.01)
    ly = SimpleNamespace(sticks=False, unbounded=unbounded, exponents=np.array([lam, lam]),
                         message=message)
    text = stability.motion_verdict(motion, ly)
    assert expect in text and "twice its error from 0" not in text


def test_strip_marks_chaos_only_where_classify_calls_it(make_explorer):
    """Undamped elastic r = 1, c = 0: λ₁ > 0 at most values, but classify calls many of
    them unbounded or undetermined. The strip's chaos marks and its title count are
    classify's on the same grid, start and window."""
    e = make_explorer(r="1", c="0")
    assert e.diagram.class_job.done.wait(120)
    data = e.lyapunov.source.data
    run = e.bifurcation.run
    kinds = {}
    for w in np.linspace(run.bif_min, run.bif_max, run.bif_n):
        sol = il.simulate(run.params.replace(omega=float(w)), t_end=run.t_end,
                          t_record=run.t_record, x0=run.x0, v0=run.v0)
        kinds[float(w)] = il.classify(sol).kind
    chaotic = sorted(w for w, k in kinds.items() if k == "chaotic")
    assert sorted(np.asarray(data["omega"])[np.asarray(data["chaos"])].tolist()) == chaotic
    lam = np.asarray(data["lyapunov"])
    assert np.count_nonzero(lam > 0) > len(chaotic)     # λ₁ > 0 alone would say more
    title = e.lyapunov.figure.title.text
    assert f"{len(chaotic)} of {run.bif_n} values chaotic" in title, title
    assert f"{sum(k == 'unbounded' for k in kinds.values())} unbounded" in title


@pytest.mark.parametrize("omega", [2.4321, 2.8123])
def test_one_omega_move_is_one_simulation_and_at_most_one_lyapunov_run(make_explorer,
                                                                        monkeypatch, omega):
    """The scene, its Poincaré section, the stability readout and the time plot's first
    window all read the scene's one run (counted where every il.simulate enters the
    engine); the readout's exponents are classify's own measurement (2.8123: not
    periodic), its one Lyapunov run."""
    from impactlib.analysis import lyapunov
    from impactlib.kernels import entry
    e = make_explorer()
    jobs = (e.scene_job, e.stability_job, e.window_job)
    for job in jobs:
        assert job.done.wait(60)
    runs, sims, lyap, windows = [], [], [], []
    real_entry, real_sim, real_ly = entry.simulate_run, il.simulate, lyapunov.lyapunov_run
    # simulate_run(m, c, k, g, r, omega, t0, x0, v0, t_record, ...)
    monkeypatch.setattr(entry, "simulate_run",
                        lambda *a: runs.append(a[9]) or real_entry(*a))
    monkeypatch.setattr(il, "simulate", lambda *a, **k: sims.append(k) or real_sim(*a, **k))
    monkeypatch.setattr(lyapunov, "lyapunov_run", lambda *a, **k: lyap.append(a) or real_ly(*a, **k))
    real_show = e.displacement.show_window
    monkeypatch.setattr(e.displacement, "show_window",
                        lambda run, cols: windows.append((run, cols)) or real_show(run, cols))
    e.settings.omega = omega
    for job in jobs:
        assert job.done.wait(60)
    assert e.readout is not None and e.readout.kind != "failed"
    # the time plot got its first window of the new run, sampled as a window of its own
    # would be (>= 48 samples per period, >= 2 per pixel of the width assumed unrendered)
    assert windows and windows[-1][0] is e.run
    t = np.asarray(windows[-1][1]["t"])
    start, end = e.run.t_end - 8 * e.run.params.T, e.run.t_end
    assert t[0] == start and t[-1] == end
    assert np.count_nonzero(np.diff(t) > 0) >= 2 * 1000 - 1
    assert runs == [e.run.t_record] and len(sims) == 1, (runs, sims)
    assert len(lyap) == (1 if e.readout.kind == "exponents" else 0)
