"""Speed benchmark of impactlib (issue 12): trajectories against an independent prototype,
bifurcation diagrams on 1 and 2 threads, the solve_ivp and rk4 alternatives, a regime map,
scaling tables, peak memory and (opt-in) a large regime map on Dask, in one run.

    .venv/bin/python bench/bench_speed.py            # full run; writes BENCHMARKS.md
    .venv/bin/python bench/bench_speed.py --dask     # ... plus a 1000 x 1000 map on Dask
    .venv/bin/python bench/bench_speed.py --quick    # smaller and fewer repeats; prints only

All timings come from this one process, after a warm-up call (Numba compilation or cache
load), as medians over repeats of ``time.perf_counter``; ratios are formed from figures of
the same run.  Memory is measured in fresh child processes (this file with ``--child``) so
that each peak starts from a clean interpreter: tracemalloc's peak (Python objects and
NumPy arrays) and the growth of ru_maxrss over the child's post-import, post-warm-up
baseline (includes everything the process touched, Numba's runtime and thread stacks).
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import re
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import impactlib as il  # noqa: E402
from impactlib.analysis.classify import describe  # noqa: E402

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)
T_END, T_RECORD = 500.0, 250.0
OMEGAS = np.linspace(0.1, 5.0, 1000)
MATCH_TOL = 1e-6            # impact-time accuracy the alternatives must reach at the paper default


# ------------------------------------------------------------------ helpers


def timed(fn, repeats, warmup=1):
    """Median, min and max wall time of fn() after warm-up calls, the median CPU time of
    the process (all its threads), and the last result."""
    out = None
    for _ in range(warmup):
        out = fn()
    ts, cpu = [], []
    for _ in range(repeats):
        c0 = time.process_time()
        tic = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - tic)
        cpu.append(time.process_time() - c0)
    return {"median": float(np.median(ts)), "min": float(min(ts)), "max": float(max(ts)),
            "cpu": float(np.median(cpu)), "n": repeats}, out


def fmt_t(s):
    if s < 1e-3:
        return f"{s * 1e6:.0f} µs"
    if s < 1.0:
        return f"{s * 1e3:.3g} ms"
    return f"{s:.3g} s"


def fmt_mb(b):
    return f"{b / 2**20:.1f} MB" if b >= 2**20 else f"{b / 2**10:.0f} kB"


def machine():
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    fam = ""
    try:
        info = Path("/proc/cpuinfo").read_text()
        f = [ln.split(":")[1].strip() for ln in info.splitlines() if ln.startswith("cpu family")]
        mo = [ln.split(":")[1].strip() for ln in info.splitlines() if ln.startswith("model\t")]
        if f and mo:
            fam = f" (family {f[0]}, model {mo[0]})"
    except OSError:
        pass
    hyp = " under a hypervisor" if "hypervisor" in Path("/proc/cpuinfo").read_text() else ""
    import numba
    import scipy
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "impactlib"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        if dirty:
            commit += " + uncommitted changes in impactlib/"
    except (OSError, subprocess.SubprocessError):
        commit = "unknown"
    return {
        "cpu": cpu + fam + hyp,
        "cores": os.cpu_count(),
        "usable_cores": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "impactlib_workers": il.sweeps.diagrams.worker_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "scipy": scipy.__version__,
        "os": platform.platform(),
        "date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit,
        "load_start": os.getloadavg(),
    }


def agreement_mask(ref, other, tol=MATCH_TOL):
    """Per value: do the recorded impacts match ref's in number and to tol in time?"""
    def per_value(b):
        kept = np.minimum(b.n_impacts, np.bincount(b.index, minlength=b.values.size))
        return np.split(b.t, np.cumsum(kept)[:-1])
    return np.array([ta.shape == tb.shape and (ta.size == 0 or np.max(np.abs(ta - tb)) <= tol)
                     for ta, tb in zip(per_value(ref), per_value(other))])


# ------------------------------------------------------------------ the solve_ivp route


def ivp_run(p, t_end=T_END, t_record=T_RECORD, method="RK45", rtol=1e-6, atol=1e-9,
            budget=10.0):
    """One run the way a user without impactlib would write it: scipy's solve_ivp on the
    flight ODE with a terminal event at x = g, restarted after each impact with
    v -> -r v.  A rebound under 1e-9 is taken as sticking: the mass rests until the net
    force cos(omega t) - k g turns outwards.  Gives up after ``budget`` seconds of wall time.

    Returns (impact times in the window, status "ok" or "gave up", t reached, restarts, nfev).
    """
    from scipy.integrate import solve_ivp

    m, c, k, g, r, om = p.m, p.c, p.k, p.g, p.r, p.omega

    def rhs(t, y):
        return [y[1], (math.cos(om * t) - 2.0 * c * y[1] - k * y[0]) / m]

    def hit(t, y):
        return y[0] - g
    hit.terminal = True
    hit.direction = -1

    t, x, v = 0.0, max(0.0, g), 0.0
    times = []
    restarts = nfev = 0
    tic = time.perf_counter()
    while t < t_end:
        if time.perf_counter() - tic > budget:
            return np.array(times), "gave up", t, restarts, nfev
        if x <= g and v <= 0.0:
            kg = k * g
            if kg >= 1.0:
                break
            if math.cos(om * t) - kg <= 0.0:
                th = 2.0 * math.pi - math.acos(max(-1.0, kg))
                n = math.floor((om * t - th) / (2.0 * math.pi))
                tr = (th + 2.0 * math.pi * n) / om
                while tr <= t:
                    n += 1
                    tr = (th + 2.0 * math.pi * n) / om
                t = tr
            x, v = g, 0.0
            if t >= t_end:
                break
        sol = solve_ivp(rhs, (t, t_end), [x, v], method=method, rtol=rtol, atol=atol,
                        events=hit)
        restarts += 1
        nfev += sol.nfev
        if sol.status != 1:
            break
        te = float(sol.t_events[0][0])
        ve = float(sol.y_events[0][0][1])
        if te >= t_record:
            times.append(te)
        t, x, v = te, g, -r * ve
        if v < 1e-9:
            v = 0.0
    return np.array(times), "ok", t_end, restarts, nfev


# ------------------------------------------------------------------ sections


def bench_prototype(cfg):
    """The independent prototype (bench/prototype.py) and simulate(), interleaved in the
    same loop so that load changes hit both alike."""
    from prototype import prototype
    t_p, v_p, n_p, ev_p = prototype(PAPER)
    ref = il.simulate(PAPER, T_END, t_record=T_RECORD)
    err = (float(np.max(np.abs(t_p - ref.impacts.t))) if t_p.shape == ref.impacts.t.shape
           else math.nan)
    for _ in range(20):
        prototype(PAPER)
        il.simulate(PAPER, T_END, t_record=T_RECORD)
    tp, ts = [], []
    for _ in range(cfg["traj_reps"]):
        tic = time.perf_counter()
        prototype(PAPER)
        tp.append(time.perf_counter() - tic)
        tic = time.perf_counter()
        il.simulate(PAPER, T_END, t_record=T_RECORD)
        ts.append(time.perf_counter() - tic)
    return {"prototype": float(np.median(tp)), "simulate": float(np.median(ts)),
            "evals": ev_p, "impacts": n_p, "err": err}


def bench_trajectory(cfg):
    res = {}
    cases = [("exact", {}), ("rk4", {"dt": 0.01}), ("rk4", {"dt": cfg["dt_match"]}),
             ("rk45", {"rtol": 1e-6, "atol": 1e-9}), ("rk45", {"rtol": 1e-9, "atol": 1e-12})]
    ref = il.simulate(PAPER, T_END, t_record=T_RECORD)
    for method, kw in cases:
        reps = cfg["traj_reps"] if method == "exact" else max(5, cfg["traj_reps"] // 10)
        st, sol = timed(lambda: il.simulate(PAPER, T_END, t_record=T_RECORD, method=method, **kw),
                        reps, warmup=2)
        kern = []
        for _ in range(reps):
            kern.append(il.simulate(PAPER, T_END, t_record=T_RECORD, method=method, **kw).elapsed)
        err = (float(np.max(np.abs(sol.impacts.t - ref.impacts.t)))
               if len(sol.impacts) == len(ref.impacts) else math.nan)
        label = method + "".join(f" {k}={v:g}" for k, v in kw.items())
        res[label] = {"call": st, "kernel": float(np.median(kern)), "nsteps": sol.nsteps,
                      "n_impacts": sol.n_impacts, "err": err}
    return res


def calibrate_rk4():
    """Largest dt (on a 2^(1/8) grid) whose impact times at the paper default, all 500 s,
    match the exact method's to MATCH_TOL (and every smaller dt of the grid too)."""
    ref = il.simulate(PAPER, T_END, t_record=0.0)
    table = []
    for i in range(40):
        dt = 0.25 * 2.0 ** (-i / 8)
        try:
            sol = il.simulate(PAPER, T_END, t_record=0.0, method="rk4", dt=dt)
        except ValueError:
            continue
        err = (float(np.max(np.abs(sol.impacts.t - ref.impacts.t)))
               if len(sol.impacts) == len(ref.impacts) else math.inf)
        table.append((dt, err))
        if dt < 0.02:
            break
    best = None
    for dt, err in reversed(table):       # from the smallest dt up
        if err <= MATCH_TOL:
            best = (dt, err)
        else:
            break
    return best, table


def calibrate_rk4_diagram(dt0):
    """The dt at which rk4 matches exact to MATCH_TOL at every periodic value of the
    diagram (every 5th omega; periodic and not chattering by the exact run's class):
    halve dt by sqrt(2) from the paper-default match until none disagrees.  Values where
    the exact run itself moves by more than MATCH_TOL when the start moves by 1e-15 (long
    chaotic transients before a periodic orbit) are left out: no method can match there."""
    sub = OMEGAS[::5]
    row = il.regime_map(PAPER, "omega", sub, "r", [PAPER.r], T_END, T_RECORD)
    periodic = (row.period[0] > 0) & (row.impacts[0] > 0)
    ref = il.bifurcation(PAPER, "omega", sub, T_END, T_RECORD)
    nudged = il.bifurcation(PAPER, "omega", sub, T_END, T_RECORD, x0=1e-15)
    periodic &= agreement_mask(ref, nudged)
    table = []
    for k in range(16):
        dt = dt0 * 2.0 ** (-k / 2)
        bif = il.bifurcation(PAPER, "omega", sub, T_END, T_RECORD, method="rk4", dt=dt)
        ok = agreement_mask(ref, bif)
        table.append((dt, int(ok[periodic].sum()), int(periodic.sum())))
        if ok[periodic].all():
            return dt, table
    return None, table


def calibrate_ivp(cfg):
    """solve_ivp settings reaching MATCH_TOL in impact times at the paper default; the
    fastest (median of a few runs) is used for the diagram."""
    ref = il.simulate(PAPER, T_END, t_record=T_RECORD)
    rows = []
    for method, rtol in [("RK45", 1e-5), ("RK45", 1e-6), ("RK45", 1e-7),
                         ("DOP853", 1e-6), ("DOP853", 1e-7), ("DOP853", 1e-8)]:
        atol = rtol * 1e-3
        st, (times, status, _, restarts, nfev) = timed(
            lambda: ivp_run(PAPER, method=method, rtol=rtol, atol=atol), cfg["ivp_cal_reps"],
            warmup=0)
        err = (float(np.max(np.abs(times - ref.impacts.t)))
               if times.shape == ref.impacts.t.shape else math.inf)
        rows.append({"method": method, "rtol": rtol, "atol": atol, "time": st["cpu"],
                     "err": err, "nfev": nfev, "restarts": restarts})
    ok = [r for r in rows if r["err"] <= MATCH_TOL]
    choice = min(ok, key=lambda r: r["time"]) if ok else min(rows, key=lambda r: r["err"])
    return choice, rows


def bench_diagram(cfg):
    res = {}
    for label, w in [("1 core", 1), ("all cores", 2)]:
        st, bif = timed(lambda: il.bifurcation(PAPER, "omega", OMEGAS, T_END, T_RECORD,
                                               workers=w), cfg["diag_reps"])
        res[label] = st
    # the Lyapunov strip's cost: the same sweep on all cores carrying the tangent
    res["lyapunov"], _ = timed(lambda: il.bifurcation(PAPER, "omega", OMEGAS, T_END, T_RECORD,
                                                      workers=2, lyapunov=True),
                               cfg["diag_reps"])
    res["rows"] = len(bif)
    res["status"] = {int(s): int(n) for s, n in zip(*np.unique(bif.status, return_counts=True))}
    res["bif"] = bif
    return res


def bench_orbit(cfg):
    """periodic_orbit with its multipliers: Newton from a start near the period-1 orbit."""
    start = il.periodic_orbit(PAPER)
    st, orb = timed(lambda: il.periodic_orbit(PAPER, 1, x0=start.x + 1e-3, v0=start.v - 1e-3),
                    cfg["traj_reps"], warmup=5)
    return {"time": st, "stable": bool(orb.stable)}


def bench_rk4_diagram(cfg, dt, exact_bif):
    res = {}
    for label, w in [("1 core", 1), ("all cores", None)]:
        st, bif = timed(lambda: il.bifurcation(PAPER, "omega", OMEGAS, T_END, T_RECORD,
                                               method="rk4", dt=dt, workers=w),
                        cfg["rk4_reps"], warmup=0)
        res[label] = st
    res["agree"] = int(agreement_mask(exact_bif, bif).sum())
    return res


def bench_ivp_diagram(cfg, choice, exact_bif):
    idx = np.unique(np.round(np.linspace(0, OMEGAS.size - 1, cfg["ivp_values"])).astype(int))
    per = []
    for i in idx:
        q = PAPER.replace(omega=float(OMEGAS[i]))
        tic = time.perf_counter()
        c0 = time.process_time()
        times, status, t_reached, restarts, nfev = ivp_run(
            q, method=choice["method"], rtol=choice["rtol"], atol=choice["atol"],
            budget=cfg["ivp_budget"])
        cpu = time.process_time() - c0
        el = time.perf_counter() - tic
        ref = exact_bif.t[exact_bif.index == i]
        agree = times.shape == ref.shape and (ref.size == 0
                                              or np.max(np.abs(times - ref)) <= MATCH_TOL)
        per.append({"omega": float(OMEGAS[i]), "time": cpu, "wall": el, "status": status,
                    "t_reached": t_reached, "restarts": restarts, "nfev": nfev,
                    "agree": bool(agree)})
    mean = float(np.mean([p["time"] for p in per]))
    wall = float(np.mean([p["wall"] for p in per]))
    return {"values": per, "mean": mean, "estimate": mean * OMEGAS.size,
            "estimate_wall": wall * OMEGAS.size,
            "gave_up": sum(p["status"] != "ok" for p in per)}


def regime_grid(n):
    return np.linspace(0.1, 5.0, n), np.linspace(0.05, 0.95, n)


def bench_map(cfg):
    n = cfg["map_n"]
    wx, wy = regime_grid(n)
    il.regime_map(PAPER, "omega", wx[::max(1, n // 8)], "r", wy[:2])     # warm-up
    st, rm = timed(lambda: il.regime_map(PAPER, "omega", wx, "r", wy), cfg["map_reps"],
                   warmup=0)
    kinds = {}
    for iy in range(0, n, max(1, n // 50)):
        for ix in range(0, n, max(1, n // 50)):
            k = describe(int(rm.impacts[iy, ix]), int(rm.period[iy, ix])).kind
            kinds[k] = kinds.get(k, 0) + 1
    return {"n": n, "time": st, "kinds_sampled": kinds}


def bench_scaling(cfg):
    """Time against t_end (one trajectory), diagram size and grid size."""
    out = {"t_end": [], "diagram": [], "grid": []}
    for t_end in cfg["scale_t_end"]:
        st, sol = timed(lambda: il.simulate(PAPER, t_end, t_record=t_end - 250.0),
                        max(3, cfg["traj_reps"] // 10))
        out["t_end"].append((t_end, st["median"], sol.n_impacts))
    for n in cfg["scale_diagram"]:
        om = np.linspace(0.1, 5.0, n)
        st, _ = timed(lambda: il.bifurcation(PAPER, "omega", om, T_END, T_RECORD, workers=2),
                      1 if n >= 10000 else 3)
        out["diagram"].append((n, st["median"], st["cpu"]))
    for n in cfg["scale_grid"]:
        wx, wy = regime_grid(n)
        st, _ = timed(lambda: il.regime_map(PAPER, "omega", wx, "r", wy, workers=2), 1,
                      warmup=0)
        out["grid"].append((n * n, st["median"], st["cpu"]))
    return out


def bench_dask(cfg):
    """A large regime map on a Dask LocalCluster (2 single-threaded worker processes)
    against the same map run locally on 2 threads."""
    from dask.distributed import Client, LocalCluster

    from impactlib.sweeps import distributed as ild
    n = cfg["dask_n"]
    wx, wy = regime_grid(n)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        # warm-up: every worker compiles or loads its Numba cache
        ild.regime_map(client, PAPER, "omega", wx[:8], "r", wy[:4])
        tic = time.perf_counter()
        rd = ild.regime_map(client, PAPER, "omega", wx, "r", wy)
        t_dask = time.perf_counter() - tic
    tic = time.perf_counter()
    rl = il.regime_map(PAPER, "omega", wx, "r", wy, workers=2)
    t_local = time.perf_counter() - tic
    same = bool(np.array_equal(rd.impacts, rl.impacts) and np.array_equal(rd.period, rl.period))
    return {"n": n, "cells": n * n, "dask": t_dask, "local": t_local, "identical": same}


def diagram_values(repeats=3):
    """Each diagram value run alone through simulate(), ``repeats`` times: per omega
    (omega, best kernel time, steps, impacts in all, chatters summed, sticking intervals)."""
    rows = []
    for om in OMEGAS:
        q = PAPER.replace(omega=float(om))
        sols = [il.simulate(q, T_END, t_record=T_RECORD) for _ in range(repeats)]
        sol = sols[0]
        rows.append((om, min(x.elapsed for x in sols), sol.nsteps, sol.n_impacts,
                     sol.n_chatter, len(sol.sticking)))
    return np.array(rows)


def profile_diagram():
    """Per-omega kernel cost of the diagram (each value run alone through simulate)."""
    a = diagram_values()
    cost = a[:, 1]
    order = np.sort(cost)[::-1]
    tot = cost.sum()
    bands = []
    edges = np.linspace(0.1, 5.0, 8)
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (a[:, 0] >= lo) & (a[:, 0] < hi + 1e-12)
        bands.append({"lo": lo, "hi": hi, "share": float(cost[sel].sum() / tot),
                      "ms_per_value": float(cost[sel].mean() * 1e3),
                      "impacts": float(a[sel, 3].mean()),
                      "steps_per_impact": float(a[sel, 2].sum() / max(1.0, a[sel, 3].sum())),
                      "chatter": int((a[sel, 4] > 0).sum())})
    # Python-side setup of a sweep: validating 1000 Params and packing constants
    tic = time.perf_counter()
    il.sweeps.diagrams._param_rows(PAPER, {"omega": OMEGAS}, "exact", None, None)
    setup = time.perf_counter() - tic
    # balance of run_jobs' dynamic hand-out on 2 threads, replayed with these costs:
    # blocks in its order and sizes, each to the thread that is free first
    nw = 2
    jorder = il.sweeps.diagrams.interleaved(OMEGAS.size)
    max_block = max(1, il.sweeps.diagrams.BLOCK_OUTPUT // il.sweeps.diagrams.CAP_PER_VALUE)
    free = [0.0] * nw
    a_ = 0
    n_blocks = 0
    while a_ < OMEGAS.size:
        b_ = min(OMEGAS.size, a_ + max(1, min(max_block, (OMEGAS.size - a_) // (4 * nw))))
        i = int(np.argmin(free))
        free[i] += float(cost[jorder[a_:b_]].sum())
        a_ = b_
        n_blocks += 1
    makespan = max(free)
    chunk_cost = free
    top = [{"omega": float(a[i, 0]), "time": float(a[i, 1]), "impacts": int(a[i, 3]),
            "evals": int(a[i, 2]), "chatter": int(a[i, 4])} for i in np.argsort(cost)[::-1][:5]]
    chat = a[:, 4] > 0
    return {"total": float(tot), "median": float(np.median(cost)), "top": top,
            "chatter_values": int(chat.sum()), "chatter_share": float(cost[chat].sum() / tot),
            "evals_per_impact_nochatter": float(a[~chat, 2].sum() / max(1.0, a[~chat, 3].sum())),
            "p90": float(np.percentile(cost, 90)), "p99": float(np.percentile(cost, 99)),
            "max": float(cost.max()), "omega_max": float(a[np.argmax(cost), 0]),
            "top10_share": float(order[:len(order) // 10].sum() / tot),
            "steps_per_impact": float(a[:, 2].sum() / a[:, 3].sum()),
            "ns_per_step": float(tot / a[:, 2].sum() * 1e9),
            "bands": bands, "setup": setup, "n_blocks": n_blocks, "chunk_cost": chunk_cost,
            "makespan": makespan}


# ------------------------------------------------------------------ memory (child processes)


def _vm(field):
    text = Path("/proc/self/status").read_text()
    return int(re.search(field + r":\s+(\d+) kB", text).group(1)) * 1024


def child(kind):
    """Run in a fresh process: warm up, then measure one workload; print JSON.

    Peak RSS: Linux's high-water mark VmHWM, reset to the current RSS just before the
    workload (echo 5 > /proc/self/clear_refs); where that is refused, ru_maxrss.
    """
    il.simulate(PAPER, 20.0, t_record=0.0)
    il.bifurcation(PAPER, "omega", OMEGAS[:4], 20.0, 0.0)
    il.regime_map(PAPER, "omega", OMEGAS[:2], "r", [0.5, 0.8], 20.0, 0.0)
    out = {}
    try:
        Path("/proc/self/clear_refs").write_text("5")
        rss0 = _vm("VmRSS")
        peak = lambda: _vm("VmHWM")  # noqa: E731
        out["rss_how"] = "VmHWM after a reset"
    except (OSError, AttributeError):
        rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        peak = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # noqa: E731
        out["rss_how"] = "ru_maxrss"
    out["rss_base"] = rss0
    tracemalloc.start()
    if kind == "diagram":
        il.bifurcation(PAPER, "omega", OMEGAS, T_END, T_RECORD)
    elif kind.startswith("map"):
        wx, wy = regime_grid(int(kind[3:]))
        il.regime_map(PAPER, "omega", wx, "r", wy)
    out["traced_peak"] = tracemalloc.get_traced_memory()[1]
    out["rss_growth"] = peak() - rss0
    out["rss_peak"] = peak()
    if kind == "diagram":
        # impacts-only runs: the same 250 s window at t_end = 500 and 5000
        for t_end in (500.0, 5000.0):
            tracemalloc.reset_peak()
            il.simulate(PAPER, t_end, t_record=t_end - 250.0)
            out[f"simulate_{t_end:g}"] = tracemalloc.get_traced_memory()[1]
            tracemalloc.reset_peak()
            il.bifurcation(PAPER, "omega", OMEGAS[::10], t_end, t_end - 250.0)
            out[f"diagram100_{t_end:g}"] = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(json.dumps(out))


def measure_memory(kind):
    proc = subprocess.run([sys.executable, __file__, "--child", kind], capture_output=True,
                          text=True, timeout=900, cwd=ROOT)
    if proc.returncode != 0:
        raise RuntimeError(f"memory child {kind} failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


# ------------------------------------------------------------------ report


def idle_estimate(r):
    """All-cores diagram wall time on an idle machine: CPU time / best chunked speed-up."""
    prof = r["prof"]
    return r["diag"]["all cores"]["cpu"] * prof["makespan"] / sum(prof["chunk_cost"])


def report(m, cfg, r):
    L = []
    add = L.append
    traj, diag, rk4d, ivp, mp, prof = (r["traj"], r["diag"], r["rk4d"], r["ivp"], r["map"],
                                       r["prof"])
    # single-threaded work is compared by CPU time (robust to other jobs taking the core);
    # wall time where threads run in parallel
    ex1, exn = diag["1 core"]["cpu"], diag["all cores"]["median"]
    add("# Speed benchmarks")
    add("")
    add(f"Written by `{cfg['command']}` on {m['date']} (commit {m['commit']}). "
        + ("**Quick mode: smaller/fewer runs; not the reference figures.** " if cfg["quick"] else "")
        + "Accuracy figures are in BENCHMARKS-accuracy.md.")
    add("")
    loads = (f"{' '.join(f'{x:.2f}' for x in m['load_start'])} / "
             f"{' '.join(f'{x:.2f}' for x in m['load_end'])}")
    if m["load_start"][0] < 1.0:
        add(f"Taken with no other job running (load average at start / end: {loads}; the "
            "benchmark's own threads raise it). Ratios are formed within one run.")
    else:
        add("**Noise warning.** These figures were taken on a shared 2-core machine while "
            f"other jobs ran (load average at start / end: {loads}). Ratios are formed "
            "within one run, so they are more robust than absolute times, but the final "
            "figures should come from a re-run on a quiet machine.")
    add("")
    add("## Machine")
    add("")
    add(f"- CPU: {m['cpu']}; {m['cores']} cores ({m['usable_cores']} usable), "
        f"impactlib thread pool: {m['impactlib_workers']}")
    add(f"- Python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, scipy {m['scipy']}")
    add(f"- {m['os']}")
    add("")
    add("## Method")
    add("")
    add("One process; every figure is the median over repeats after a warm-up call "
        "(`time.perf_counter`); `[min-max]` shows the spread. Paper defaults: m=1, c=0.05, k=1, "
        "g=0, r=0.8, omega=2; runs to t_end=500 keeping t >= 250 (the paper's window). "
        "Memory is measured in fresh child processes (see Memory).")
    add("")
    add("## 1. One 500 s trajectory at the paper defaults")
    add("")
    add("| method | `simulate()` call | kernel only | steps | impacts | max impact-time error vs exact |")
    add("|---|---|---|---|---|---|")
    for label, v in traj.items():
        err = "-" if label == "exact" else (f"{v['err']:.1e}" if math.isfinite(v["err"]) else "count differs")
        add(f"| {label} | {fmt_t(v['call']['median'])} [{fmt_t(v['call']['min'])}-{fmt_t(v['call']['max'])}] "
            f"| {fmt_t(v['kernel'])} | {v['nsteps']} | {v['n_impacts']} | {err} |")
    add("")
    add("Steps: closed-form evaluations (exact; the grid nodes of the search, advanced by a "
        "recurrence without transcendental functions, are not counted) or integrator steps. "
        "The error column compares the impacts of the record window with the exact method's.")
    add("")
    pr = r["proto"]
    add(f"Independent prototype of the exact method (`bench/prototype.py`: plain closed form, "
        f"cubic safe step, Newton near a crossing; {pr['evals']} evaluations for "
        f"{pr['impacts']} impacts, impact times within {pr['err']:.1e} of simulate()), timed "
        f"alternately with `simulate()` in one loop: prototype {fmt_t(pr['prototype'])}, "
        f"simulate() {fmt_t(pr['simulate'])} per trajectory: "
        f"**{pr['simulate'] / pr['prototype']:.2f}x**.")
    add("")
    add("### Matched accuracy (how the rk4 step and the solve_ivp tolerance were chosen)")
    add("")
    dt, err = r["dt_match"]
    add(f"rk4: the largest dt on a 2^(1/8) grid whose impact times over the whole 500 s at the "
        f"paper default (all {traj['exact']['n_impacts']} impacts) match exact to {MATCH_TOL:g}: "
        f"**dt = {dt:.4g}** (max error {err:.2g}; the error falls as dt^4: "
        + ", ".join(f"dt={d:.3g}: {e:.1e}" for d, e in r["dt_table"][::4]) + ").")
    add("")
    add("solve_ivp route (terminal event at x=g, a restart per impact, a rebound under 1e-9 taken "
        "as sticking until the wall force turns outwards; plain Python right-hand side; "
        "atol = rtol/1000), at the paper default:")
    add("")
    add("| solver | rtol | one 500 s run | max impact-time error | nfev | restarts |")
    add("|---|---|---|---|---|---|")
    for row in r["ivp_cal"]:
        add(f"| {row['method']} | {row['rtol']:g} | {fmt_t(row['time'])} | {row['err']:.1e} | "
            f"{row['nfev']} | {row['restarts']} |")
    c = r["ivp_choice"]
    add("")
    add(f"Used for the diagram: **{c['method']} rtol={c['rtol']:g}, atol={c['atol']:g}**, the "
        f"fastest that reaches {MATCH_TOL:g}.")
    add("")
    add("## 2. 1000-value omega diagram on [0.1, 5], r = 0.8, exact")
    add("")
    add("| | wall | CPU time of the process | rows |")
    add("|---|---|---|---|")
    for label in ("1 core", "all cores"):
        s = diag[label]
        add(f"| exact, {'1 thread' if label == '1 core' else '2 threads'} | {fmt_t(s['median'])} [{fmt_t(s['min'])}-{fmt_t(s['max'])}] | "
            f"{fmt_t(s['cpu'])} | {diag['rows']} |")
    s = diag["lyapunov"]
    add(f"| exact with lyapunov=True, 2 threads | {fmt_t(s['median'])} [{fmt_t(s['min'])}-"
        f"{fmt_t(s['max'])}] | {fmt_t(s['cpu'])} | {diag['rows']} |")
    add("")
    add(f"Parallel speed-up {diag['1 core']['median'] / exn:.2f}x (wall) on "
        f"{m['impactlib_workers']} threads. "
        f"Run status per value: {diag['status']} (0 = reached t_end).")
    share = diag["1 core"]["cpu"] / diag["1 core"]["median"]
    if share < 0.85:
        add("")
        add(f"**This run shared its cores with other jobs**: the 1-core diagram got {share:.0%} "
            f"of a core (CPU time / wall time). On an idle machine its wall time would be its CPU "
            f"time, and the all-cores wall time about the CPU time divided by the best speed-up "
            f"the chunking allows (see Profile): {fmt_t(idle_estimate(r))} (an estimate, not a "
            "measurement).")
    add("")
    add("## 3. The same diagram without this project")
    add("")
    add("1-core figures are CPU time of the process (wall time in brackets): on a shared "
        "machine CPU time does not count the time other jobs held the core. All-core figures "
        "are wall time.")
    add("")
    add(f"| route | 1000-value diagram, 1 core | all cores | exact is faster by, 1 core vs 1 core "
        f"(exact: {fmt_t(ex1)}) | all cores vs all cores (exact: {fmt_t(exn)}) |")
    add("|---|---|---|---|---|")
    add(f"| solve_ivp {c['method']} rtol={c['rtol']:g}, a restart per impact (**estimated**: "
        f"{len(ivp['values'])} values timed, mean x 1000; a single-threaded script) | "
        f"{fmt_t(ivp['estimate'])} ({fmt_t(ivp['estimate_wall'])}) | - | "
        f"**{ivp['estimate'] / ex1:.0f}x** | {ivp['estimate'] / exn:.0f}x (against its 1 core) |")
    rk4_rows = [(f"dt={dt:.4g}, matched at the paper default", rk4d)]
    if r["dt_wide"] is not None:
        rk4_rows.append((f"dt={r['dt_wide']:.4g}, matched at every periodic value", r["rk4d_wide"]))
    for label, w in rk4_rows:
        add(f"| our rk4, {label} | {fmt_t(w['1 core']['cpu'])} ({fmt_t(w['1 core']['median'])}) | "
            f"{fmt_t(w['all cores']['median'])} | **{w['1 core']['cpu'] / ex1:.1f}x** | "
            f"{w['all cores']['median'] / exn:.1f}x |")
    add("")
    add("solve_ivp subset: omega = " + ", ".join(f"{p['omega']:.3g}" for p in ivp["values"]) + "; "
        f"per value {fmt_t(min(p['time'] for p in ivp['values']))} to "
        f"{fmt_t(max(p['time'] for p in ivp['values']))}; "
        f"{ivp['gave_up']} value(s) hit the {cfg['ivp_budget']:g} s per-value budget and were "
        "counted at the budget (so the estimate is a lower bound)"
        + (": " + ", ".join(f"omega={p['omega']:.3g} (reached t={p['t_reached']:.4g})"
                            for p in ivp["values"] if p["status"] != "ok") if ivp["gave_up"] else "")
        + f". Window impacts matching exact to {MATCH_TOL:g}: "
        f"{sum(p['agree'] for p in ivp['values'])} of {len(ivp['values'])} values "
        "(chaotic values diverge for any method; in chattering ones solve_ivp resolves hops "
        "that exact sums).")
    add("")
    add(f"rk4 at the step matched at the paper default agrees with exact to {MATCH_TOL:g} in "
        f"{rk4d['agree']} of 1000 diagram values: a match at one stable periodic orbit does not "
        f"carry over to the whole diagram (higher omega, grazing and chattering values need "
        f"smaller steps). Matching at every periodic, non-chattering value (every 5th omega, "
        f"class from the exact run) takes: "
        + ", ".join(f"dt={d:.3g}: {a}/{n}" for d, a, n in r["dt_wide_table"])
        + (f"; that dt agrees in {r['rk4d_wide']['agree']} of 1000 values."
           if r["dt_wide"] is not None else "; no tried dt reached all of them."))
    add("")
    add(f"## 4. {mp['n']} x {mp['n']} regime map (omega in [0.1, 5] x r in [0.05, 0.95])")
    add("")
    s = mp["time"]
    add(f"exact, all cores: **{fmt_t(s['median'])}** [{fmt_t(s['min'])}-{fmt_t(s['max'])}] "
        f"over {s['n']} run(s), {mp['n'] ** 2} cells, "
        f"{fmt_t(s['cpu'] / mp['n'] ** 2)} of CPU per cell. "
        f"Kinds on a sample of cells: {mp['kinds_sampled']}.")
    add("")
    add("## 5. Memory")
    add("")
    add("Each workload runs in a fresh child process after import and a warm-up: "
        "`tracemalloc` peak (Python objects and NumPy arrays, all threads) and the growth of the "
        f"process's peak RSS over its resident size just before the workload "
        f"({r['mem']['diagram']['rss_how']}; whole process, so it includes the Numba runtime and "
        f"thread stacks). Baseline RSS after import and warm-up: "
        f"{fmt_mb(r['mem']['diagram']['rss_base'])}.")
    add("")
    add("| workload | tracemalloc peak | peak RSS growth | process peak RSS |")
    add("|---|---|---|---|")
    for label, key in [("1000-value diagram (all cores)", "diagram"),
                       (f"{mp['n']} x {mp['n']} regime map", "map")]:
        v = r["mem"][key]
        add(f"| {label} | {fmt_mb(v['traced_peak'])} | {fmt_mb(v['rss_growth'])} | {fmt_mb(v['rss_peak'])} |")
    d = r["mem"]["diagram"]
    add("")
    add("Impacts-only runs keep only the window, so memory does not grow with t_end "
        "(tracemalloc peak, same 250 s window):")
    add("")
    add("| run | t_end = 500 | t_end = 5000 |")
    add("|---|---|---|")
    add(f"| one simulate() | {fmt_mb(d['simulate_500'])} | {fmt_mb(d['simulate_5000'])} |")
    add(f"| 100-value diagram | {fmt_mb(d['diagram100_500'])} | {fmt_mb(d['diagram100_5000'])} |")
    add("")
    add("## Targets (issues 12 and 18)")
    add("")
    add("Where issue 18 sharpened a target of issue 12 (trajectory, ratio, diagram), the "
        "sharper one is listed. The section \"Issue 18's targets: where the time goes\" "
        "below (bench/bench_misses.py) profiles each of issue 18's.")
    add("")
    tr = traj["exact"]
    pr, sc = r["proto"], r["scale"]
    speedup = diag["1 core"]["median"] / exn
    lya = diag["lyapunov"]["median"] / exn
    orb = r["orbit"]["time"]["median"]
    rm_s = mp["time"]["median"]
    targets = [
        ("one exact 500 s trajectory <= 50 µs per simulate() call",
         f"{fmt_t(tr['call']['median'])} per call, {fmt_t(tr['kernel'])} in the kernel",
         tr["call"]["median"] <= 50e-6),
        ("... and <= 0.7x the independent prototype (same loop)",
         f"{pr['simulate'] / pr['prototype']:.2f}x ({fmt_t(pr['simulate'])} vs "
         f"{fmt_t(pr['prototype'])})", pr["simulate"] <= 0.7 * pr["prototype"]),
        ("1000-value diagram <= 50 ms on 2 threads", fmt_t(exn), exn <= 0.050),
        ("2-thread speed-up >= 1.9x", f"{speedup:.2f}x (wall; CPU share of the 1-thread run "
         f"{share:.0%})", speedup >= 1.9),
        ("the same diagram with lyapunov=True <= 1.3x", f"{lya:.2f}x "
         f"({fmt_t(diag['lyapunov']['median'])})", lya <= 1.3),
        ("a periodic orbit with multipliers <= 100 µs", f"{fmt_t(orb)} (period 1, Newton from a "
         "start 1e-3 off the orbit)", orb <= 100e-6),
        (">= 2000x faster than the solve_ivp route per core",
         f"{ivp['estimate'] / ex1:.0f}x per core (CPU)", ivp["estimate"] / ex1 >= 2000),
    ]
    if r["dt_wide"] is not None:
        wr = r["rk4d_wide"]["1 core"]["cpu"] / ex1
        targets.append((">= 25x faster than rk4 at the step matching exact to 1e-6 over the diagram",
                        f"{wr:.1f}x per core (CPU; dt={r['dt_wide']:.4g})", wr >= 25))
    targets += [
        (f"{mp['n']} x {mp['n']} regime map <= 2.5 s" if mp["n"] == 200 else
         f"{mp['n']} x {mp['n']} regime map (quick; the target is for 200 x 200)",
         fmt_t(rm_s), rm_s <= 2.5),
        ("peak memory of the diagram < 200 MB", f"{fmt_mb(d['traced_peak'])} traced, "
         f"{fmt_mb(d['rss_growth'])} RSS growth", max(d["traced_peak"], d["rss_growth"]) < 200 * 2**20),
        ("memory independent of t_end (impacts only)",
         f"{fmt_mb(d['diagram100_500'])} vs {fmt_mb(d['diagram100_5000'])}",
         d["diagram100_5000"] <= 1.1 * d["diagram100_500"] + 2**20),
    ]
    add("| target | measured | |")
    add("|---|---|---|")
    for name, val, ok in targets:
        add(f"| {name} | {val} | {'met' if ok else '**missed**'} |")
    add("")
    add("## Profile of the diagram")
    add("")
    add(f"Each of the 1000 values run alone through `simulate()` (kernel time, best of 3): total "
        f"{fmt_t(prof['total'])}, median {fmt_t(prof['median'])}, p90 {fmt_t(prof['p90'])}, "
        f"p99 {fmt_t(prof['p99'])}, max {fmt_t(prof['max'])} (omega={prof['omega_max']:.3g}); the "
        f"costliest 10% of values take {prof['top10_share']:.0%} of the time. "
        f"{prof['steps_per_impact']:.1f} closed-form evaluations per impact, "
        f"{prof['ns_per_step']:.0f} ns per evaluation (including the search around it). "
        f"Python-side setup of a sweep (1000 Params validated and packed): {fmt_t(prof['setup'])}. "
        f"The {prof['chatter_values']} values with complete chattering (chatter sequences summed "
        f"to their accumulation point) take {prof['chatter_share']:.0%} of the time: each "
        "sequence resolves its hops one by one until the error bound of summing the rest "
        "is at rounding level (chatter.tail_bound). "
        f"Without them: {prof['evals_per_impact_nochatter']:.1f} evaluations per impact. "
        "Costliest values: "
        + "; ".join(f"omega={t['omega']:.3f}: {fmt_t(t['time'])}, {t['impacts']} impacts, "
                    f"{t['evals']} evaluations, {t['chatter']} chatter sums" for t in prof["top"])
        + ".")
    add("")
    add("| omega band | share of time | ms per value | impacts per value | evaluations per impact | values with summed chatter |")
    add("|---|---|---|---|---|---|")
    for b in prof["bands"]:
        add(f"| {b['lo']:.2f}-{b['hi']:.2f} | {b['share']:.0%} | {b['ms_per_value']:.2f} | "
            f"{b['impacts']:.0f} | {b['steps_per_impact']:.1f} | {b['chatter']} |")
    add("")
    rk = traj[f"rk4 dt={dt:g}"]
    ex = traj["exact"]
    rk_ns = rk["kernel"] / rk["nsteps"] * 1e9
    ex_ns = ex["kernel"] / ex["nsteps"] * 1e9
    add(f"Why rk4 at the paper-default match is close: there rk4 needs {rk['nsteps'] / rk['n_impacts']:.0f} "
        f"steps per impact at {rk_ns:.0f} ns each, exact {ex['nsteps'] / ex['n_impacts']:.1f} "
        f"closed-form evaluations per impact at {ex_ns:.0f} ns each (kernel time / evaluations, "
        f"search included), a cost ratio of {rk['kernel'] / ex['kernel']:.1f}x for one trajectory. "
        f"20x at that step would need exact at about "
        f"{rk['kernel'] / 20 / ex_ns * 1e9 / ex['n_impacts']:.1f} evaluations per impact at "
        "today's cost per evaluation.")
    add("")
    cc = prof["chunk_cost"]
    add(f"`bifurcation()` hands the 1000 values to 2 threads through `run_jobs`: blocks in an "
        f"interleaved order taken from a shared counter, shrinking as the values run out "
        f"({prof['n_blocks']} blocks). Replayed with the per-value costs above, the threads "
        f"get {fmt_t(cc[0])} and {fmt_t(cc[1])}: the best possible speed-up of this schedule "
        f"is {sum(cc) / prof['makespan']:.2f}x (the rest of any shortfall is the machine: "
        "other jobs, the Python part of each block, memory bandwidth).")
    add("")
    add("## Scaling")
    add("")
    add("Time against the length of a run (one trajectory, window the last 250 s), the number "
        "of diagram values (2 threads) and the number of regime-map cells (2 threads):")
    add("")
    add("| t_end | one simulate() | impacts | per 1000 s of run |")
    add("|---|---|---|---|")
    for t_end, t, n in sc["t_end"]:
        add(f"| {t_end:g} | {fmt_t(t)} | {n} | {fmt_t(t / t_end * 1000)} |")
    add("")
    add("| diagram values | wall | CPU | wall per value |")
    add("|---|---|---|---|")
    for n, t, c in sc["diagram"]:
        add(f"| {n} | {fmt_t(t)} | {fmt_t(c)} | {fmt_t(t / n)} |")
    add("")
    add("| regime-map cells | wall | CPU | wall per cell |")
    add("|---|---|---|---|")
    for n, t, c in sc["grid"]:
        add(f"| {n} | {fmt_t(t)} | {fmt_t(c)} | {fmt_t(t / n)} |")
    add("")
    add("Linear in each: the constant is the last column (the smallest sizes carry the fixed "
        "setup and the thread hand-off).")
    add("")
    dk = r.get("dask")
    add("## Dask")
    add("")
    if dk is None:
        add("Not run (opt-in: `--dask`, several minutes).")
    else:
        add(f"{dk['n']} x {dk['n']} = {dk['cells']:,} cells (omega x r as above) on a Dask "
            f"LocalCluster of 2 single-threaded worker processes: **{fmt_t(dk['dask'])}**, "
            f"{dk['cells'] / dk['dask']:,.0f} cells/s; the same map locally on 2 threads: "
            f"{fmt_t(dk['local'])}, {dk['cells'] / dk['local']:,.0f} cells/s. Overhead of the "
            f"cluster: {(dk['dask'] / dk['local'] - 1):+.0%}. Maps identical: {dk['identical']}.")
    add("")
    return "\n".join(L) + "\n", targets


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats and values; print only")
    ap.add_argument("--write", action="store_true", help="with --quick: write BENCHMARKS.md anyway")
    ap.add_argument("--out", default=str(ROOT / "BENCHMARKS.md"))
    ap.add_argument("--dask", action="store_true",
                    help="also a 1000 x 1000 regime map on a Dask LocalCluster (several minutes)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child)
        return
    q = args.quick
    cfg = {"quick": q, "traj_reps": 50 if q else 300, "diag_reps": 3 if q else 7,
           "rk4_reps": 1 if q else 3, "rk4_wide_reps": 1 if q else 2, "ivp_values": 6 if q else 20,
           "ivp_budget": 2.0 if q else 10.0, "ivp_cal_reps": 1 if q else 3,
           "map_n": 60 if q else 200, "map_reps": 1 if q else 2,
           "scale_t_end": [500.0, 5000.0, 50000.0],
           "scale_diagram": [100, 1000] if q else [100, 1000, 10000],
           "scale_grid": [50, 100] if q else [50, 100, 200, 400],
           "dask_n": 200 if q else 1000,
           "command": ".venv/bin/python bench/bench_speed.py" + (" --quick" if q else "")}
    m = machine()
    tic = time.perf_counter()
    log = lambda s: print(f"[{time.perf_counter() - tic:6.1f} s] {s}", flush=True)  # noqa: E731
    r = {}
    log("calibrating rk4 dt")
    best, table = calibrate_rk4()
    r["dt_match"], r["dt_table"] = best, table
    cfg["dt_match"] = best[0]
    log(f"  dt = {best[0]:.4g} (error {best[1]:.2g})")
    log("1. trajectories")
    r["traj"] = bench_trajectory(cfg)
    r["proto"] = bench_prototype(cfg)
    log(f"  simulate / prototype = {r['proto']['simulate'] / r['proto']['prototype']:.2f}")
    r["orbit"] = bench_orbit(cfg)
    log(f"  periodic_orbit {fmt_t(r['orbit']['time']['median'])}")
    log("2. 1000-value diagram, exact")
    r["diag"] = bench_diagram(cfg)
    log(f"  1 core {fmt_t(r['diag']['1 core']['median'])}, all {fmt_t(r['diag']['all cores']['median'])}")
    log("3a. rk4 diagram at the matched dt")
    r["rk4d"] = bench_rk4_diagram(cfg, best[0], r["diag"]["bif"])
    log("3a'. rk4 dt matching exact across the diagram")
    r["dt_wide"], r["dt_wide_table"] = calibrate_rk4_diagram(best[0])
    if r["dt_wide"] is not None:
        log(f"  dt = {r['dt_wide']:.4g}")
        r["rk4d_wide"] = bench_rk4_diagram(dict(cfg, rk4_reps=cfg["rk4_wide_reps"]), r["dt_wide"],
                                           r["diag"]["bif"])
    log("3b. solve_ivp calibration")
    r["ivp_choice"], r["ivp_cal"] = calibrate_ivp(cfg)
    log(f"  using {r['ivp_choice']['method']} rtol={r['ivp_choice']['rtol']:g}")
    log("3c. solve_ivp diagram subset")
    r["ivp"] = bench_ivp_diagram(cfg, r["ivp_choice"], r["diag"]["bif"])
    log("4. regime map")
    r["map"] = bench_map(cfg)
    log("scaling")
    r["scale"] = bench_scaling(cfg)
    if args.dask:
        log(f"dask: {cfg['dask_n']}^2 regime map")
        r["dask"] = bench_dask(cfg)
    log("5. memory (child processes)")
    r["mem"] = {"diagram": measure_memory("diagram"), "map": measure_memory(f"map{cfg['map_n']}")}
    log("profile")
    r["prof"] = profile_diagram()
    m["load_end"] = os.getloadavg()
    text, targets = report(m, cfg, r)
    print()
    print(text)
    if not q or args.write:
        Path(args.out).write_text(text)
        log(f"wrote {args.out}")
    log("done")


if __name__ == "__main__":
    main()
