"""Issue 18's speed targets, met or missed, with a profile of where the time goes: one
simulate() call, the 1000-value diagram and the regime map, in one process.

    .venv/bin/python bench/bench_misses.py            # prints
    .venv/bin/python bench/bench_misses.py --write    # ... and writes its section of BENCHMARKS.md

1. One exact 500 s trajectory at the paper defaults, interleaved call by call with the
   independent prototype (bench/prototype.py): the call, the engine's part of it
   (``Solution.elapsed``: the jitted entry with Numba's dispatch), the closed-form
   evaluations of each (``nsteps``; the prototype counts its own), hence the cost per
   evaluation and the evaluations per impact of each.
2. The 1000-value omega diagram: wall on 1 and 2 threads, the process's CPU time over
   the 2-thread run, and the kernel time of every value run alone (bench_speed's
   profile_diagram): the sum is the work, the rest of the 1-thread wall is Python around
   the blocks; the values with a summed chatter, and the best makespan of the blocks'
   schedule on 2 threads.
3. The 200 x 200 regime map: wall, CPU time, and the same cells' kernel time estimated from
   a sample of cells run alone (every 8th omega and r).

Medians after a warm-up. On a shared machine compare the figures of one run only.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import impactlib as il  # noqa: E402
from bench_speed import OMEGAS, PAPER, T_END, T_RECORD, profile_diagram, regime_grid  # noqa: E402
from bench_stability import write_section  # noqa: E402
from impactlib.kernels import engine as E  # noqa: E402
from impactlib.kernels.entry import simulate_run  # noqa: E402
from impactlib.model import RunLimits, check_run  # noqa: E402
from prototype import prototype  # noqa: E402

BEGIN, END = "<!-- bench_misses:begin -->", "<!-- bench_misses:end -->"


def wall_and_cpu(fn):
    c0, w0 = time.process_time(), time.perf_counter()
    fn()
    return time.perf_counter() - w0, time.process_time() - c0


def trajectory(calls):
    """simulate() against the prototype, interleaved; the call split into its parts."""
    run = lambda: il.simulate(PAPER, T_END, t_record=T_RECORD)  # noqa: E731
    sol = run()
    _, _, n_p, ev_p = prototype(PAPER)
    none = np.empty(0)
    limits = RunLimits()        # as simulate()'s default: made once
    parts = {
        "call": run,
        "prototype": lambda: prototype(PAPER),
        "check_run": lambda: check_run(PAPER, t_end=T_END, t_record=T_RECORD, x0=None, v0=0.0,
                                       phase=0.0, method="exact", dt=None, rtol=1e-6,
                                       atol=1e-9, dense=0, limits=limits),
        # a run of length 0: the entry's fixed cost (Numba's dispatch of its 19 arguments,
        # the run's constants and its output array)
        "empty engine run": lambda: simulate_run(PAPER.m, PAPER.c, PAPER.k, PAPER.g, PAPER.r,
                                                 PAPER.omega, 0.0, 0.0, 0.0, 0.0, 1e-300,
                                                 0.0, E.EXACT, 0.0, 1e-6, 1e-9, 1e6,
                                                 limits.max_steps, none),
    }
    for fn in parts.values():
        for _ in range(50):
            fn()
    times = {k: [] for k in parts}
    kern = []
    for _ in range(calls):
        for k, fn in parts.items():
            tic = time.perf_counter()
            out = fn()
            times[k].append(time.perf_counter() - tic)
            if k == "call":
                kern.append(out.elapsed)
    med = {k: float(np.median(v)) for k, v in times.items()}
    med["kernel"] = float(np.median(kern))
    return dict(med, evals=sol.nsteps, impacts=sol.n_impacts, proto_evals=int(ev_p),
                proto_impacts=int(n_p))


def machine_ceiling(reps, n=1000):
    """What two threads of this machine give a jitted, GIL-free workload with nothing
    between its calls: n paper-default runs of the engine's entry on one thread, against
    n on each of two threads at once (interleaved repeats, medians)."""
    none = np.empty(0)
    limits = RunLimits()

    def work():
        for _ in range(n):
            simulate_run(PAPER.m, PAPER.c, PAPER.k, PAPER.g, PAPER.r, PAPER.omega, 0.0, 0.0,
                         0.0, T_RECORD, T_END, 0.0, E.EXACT, 0.0, 1e-6, 1e-9, 1e6,
                         limits.max_steps, none)

    work()
    one, two = [], []
    for _ in range(reps):
        tic = time.perf_counter()
        work()
        one.append(time.perf_counter() - tic)
        threads = [threading.Thread(target=work) for _ in range(2)]
        tic = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        two.append(time.perf_counter() - tic)
    return 2 * float(np.median(one)) / float(np.median(two))


def diagram(reps):
    def one(w):
        return lambda: il.bifurcation(PAPER, "omega", OMEGAS, T_END, T_RECORD, workers=w)
    for w in (1, 2):
        one(w)()
    w1, c1, w2, c2 = [], [], [], []
    for _ in range(reps):
        w, c = wall_and_cpu(one(1))
        w1.append(w)
        c1.append(c)
        w, c = wall_and_cpu(one(2))
        w2.append(w)
        c2.append(c)
    prof = profile_diagram()
    return {"wall1": float(np.median(w1)), "cpu1": float(np.median(c1)),
            "wall2": float(np.median(w2)), "cpu2": float(np.median(c2)), "prof": prof,
            "ceiling": machine_ceiling(max(reps, 9))}


def regime(n, stride=8):
    wx, wy = regime_grid(n)
    il.regime_map(PAPER, "omega", wx[::stride], "r", wy[:2])        # warm-up
    wall, cpu = wall_and_cpu(lambda: il.regime_map(PAPER, "omega", wx, "r", wy))
    kern = []
    for y in wy[::stride]:
        for x in wx[::stride]:
            q = PAPER.replace(omega=float(x), r=float(y))
            kern.append(min(il.simulate(q, T_END, t_record=T_RECORD).elapsed for _ in range(2)))
    return {"n": n, "wall": wall, "cpu": cpu, "kernel_per_cell": float(np.mean(kern)),
            "sampled": len(kern)}


def us(s):
    return f"{s * 1e6:.1f} µs"


def ms(s):
    return f"{s * 1e3:.1f} ms"


def _met(ok: bool) -> str:
    return "**met**" if ok else "**missed**"


def markdown(t, d, m):
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                            capture_output=True).stdout.strip() or "?"
    loads = os.getloadavg()
    load = " ".join(f"{v:.2f}" for v in loads)
    quiet = loads[0] < 1.5
    p = d["prof"]
    layer = t["call"] - t["kernel"]
    if t["call"] <= 0.7 * t["prototype"]:
        verdict = "The call is within 0.7x"
    elif t["kernel"] <= 0.7 * t["prototype"]:
        verdict = "The engine's part is within 0.7x; the call misses the ratio by the Python layer"
    else:
        verdict = "The engine's part alone is above 0.7x"
    verdict += (", and 50 µs by the engine's part alone." if t["kernel"] > 50e-6 else
                "; the engine's part is within 50 µs.")
    n_cells = m["n"] ** 2
    traj_ok = t["call"] <= 50e-6 and t["call"] <= 0.7 * t["prototype"]
    diag_ok = d["wall2"] <= 50e-3 and d["wall1"] / d["wall2"] >= 1.9
    map_ok = m["wall"] <= 2.5
    split = (f"the values' kernel times (each run alone, best of 3) sum to "
             f"{ms(p['total'])}")
    split += ("" if diag_ok else
              ": 50 ms on 2 threads needs that under 100 ms even with a perfect split")
    cell_need = 2 * 2.5 / n_cells
    cells = (f"{us(m['cpu'] / n_cells)} of CPU per cell against {us(m['kernel_per_cell'])} "
             f"of kernel per cell run alone ({m['sampled']} cells sampled, every 8th ω and "
             f"r)")
    cells += ("; the rest per cell is classification and the sweep's Python" if map_ok else
              f": 2.5 s on 2 threads needs <= {us(cell_need)} of CPU per cell")
    rows = [
        "## Issue 18's targets: where the time goes (profile)",
        "",
        f"Written by `.venv/bin/python bench/bench_misses.py --write` on "
        f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC (commit {commit}; load "
        f"average at the end {load}). "
        + ("Measured on a quiet machine. " if quiet else
           "**Measured on a loaded machine** (other jobs on the cores): the absolute times "
           "are not the idle machine's. ")
        + "Ratios and counts are from one process, interleaved.",
        "",
        "| target | measured here | | what the profile shows |",
        "|---|---|---|---|",
        f"| one exact 500 s trajectory <= 50 µs per call, <= 0.7x the prototype "
        f"| {us(t['call'])} per call, {t['call'] / t['prototype']:.2f}x the prototype "
        f"({us(t['prototype'])}) | {_met(traj_ok)} "
        f"| the engine's part (`Solution.elapsed`, around the jitted entry) is "
        f"{us(t['kernel'])}, {t['kernel'] / t['prototype']:.2f}x the prototype "
        f"({t['evals']} closed-form evaluations for {t['impacts']} impacts, the grid nodes "
        f"between them not counted; the prototype {t['proto_evals']} for "
        f"{t['proto_impacts']}); of it {us(t['empty engine run'])} is the entry's fixed "
        f"cost (a run of length 0: Numba's dispatch of 19 scalar arguments, the run's "
        f"constants and output array). The Python layer around it is {us(layer)} "
        f"({100 * layer / t['call']:.0f}% of the call): validation {us(t['check_run'])}, "
        f"the result objects the rest ({us(max(0.0, layer - t['check_run']))}). "
        f"{verdict} |",
        f"| 1000-value diagram <= 50 ms on 2 threads, speed-up >= 1.9x "
        f"| {ms(d['wall2'])} on 2 threads ({ms(d['cpu2'])} CPU), {ms(d['wall1'])} on 1 "
        f"({ms(d['cpu1'])} CPU): {d['wall1'] / d['wall2']:.2f}x | {_met(diag_ok)} "
        f"| {split}; the "
        f"{p['chatter_values']} values with a summed chatter take "
        f"{100 * p['chatter_share']:.0f}% of it (each chatter resolved hop by hop until "
        f"the tail is summed); the blocks' schedule allows {p['total'] / p['makespan']:.2f}x "
        f"({p['n_blocks']} blocks). CPU of the 1-thread sweep beyond the kernels: "
        f"{ms(max(0.0, d['cpu1'] - p['total']))} (sweep setup {ms(p['setup'])}; the rest "
        f"is each block's Python and the output). With 2 threads the process got "
        f"{d['cpu2'] / d['wall2']:.2f} cores on this machine; the engine alone, as two "
        f"independent threads with nothing between its calls, scales "
        f"{d['ceiling']:.2f}x here (the machine's ceiling for this work) |",
        f"| {m['n']} x {m['n']} regime map <= 2.5 s "
        f"| {m['wall']:.2f} s wall, {m['cpu']:.2f} s CPU | {_met(map_ok)} | {cells} |",
    ]
    return "\n".join([BEGIN] + rows + [END]) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="write the section of BENCHMARKS.md")
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--map", type=int, default=200)
    args = ap.parse_args()
    t = trajectory(args.calls)
    print("trajectory", t, flush=True)
    d = diagram(args.reps)
    print("diagram", {k: v for k, v in d.items() if k != "prof"}, flush=True)
    m = regime(args.map)
    print("map", m, flush=True)
    text = markdown(t, d, m)
    print(text)
    if args.write:
        write_section(text, BEGIN, END)


if __name__ == "__main__":
    main()
