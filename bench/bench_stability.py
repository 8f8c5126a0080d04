"""Speed of the stability tools (issue 8), in one process, after warm-up, as medians.

    .venv/bin/python bench/bench_stability.py            # full run (about a minute)
    .venv/bin/python bench/bench_stability.py --quick    # fewer repeats
    .venv/bin/python bench/bench_stability.py --json out.json
    .venv/bin/python bench/bench_stability.py --write    # also its section of BENCHMARKS.md

``--write`` replaces the section between the stability markers at the end of BENCHMARKS.md
(appending it if absent); bench_speed.py rewrites that file, so run this one after it.

Targets from the issue:
  * a period-1 orbit with its multipliers in under 1 ms (Newton from a start on the
    section; the default start adds one settling run, timed separately);
  * the Lyapunov strip of a 400-value diagram adds at most 50% to the diagram's time
    (``bifurcation(..., lyapunov=True)`` against ``lyapunov=False``, same process, same
    values, alternated);
  * a continuation over omega in [1, 5] with its events in under 1 s (the paper's
    period-1 orbit followed from omega = 2 down to 1 and up to 5).
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import impactlib as il  # noqa: E402

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)


def timed(fn, repeats, warmup=1):
    out = None
    for _ in range(warmup):
        out = fn()
    ts = []
    for _ in range(repeats):
        tic = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - tic)
    return {"median": float(np.median(ts)), "min": float(min(ts)), "max": float(max(ts)),
            "repeats": repeats}, out


def bench_orbit(repeats):
    start = il.periodic_orbit(PAPER)
    res, orb = timed(lambda: il.periodic_orbit(PAPER, 1, x0=start.x + 1e-3, v0=start.v - 1e-3),
                     repeats * 50)
    res_default, _ = timed(lambda: il.periodic_orbit(PAPER), repeats * 5)
    return {"from_start_s": res, "default_start_s": res_default, "iterations": orb.iterations,
            "multipliers": [str(m) for m in orb.multipliers]}


def bench_strip(repeats, n_values=400):
    """Wall time on all cores, and CPU time on one worker (less distorted by other jobs
    on a shared machine); the two variants alternate so that load changes hit both."""
    values = np.linspace(0.5, 5.0, n_values)
    kw = dict(t_end=500.0, t_record=250.0)
    il.bifurcation(PAPER, "omega", values[:8], lyapunov=True, **kw)      # warm-up
    il.bifurcation(PAPER, "omega", values[:8], **kw)
    out = {"values": n_values, "repeats": repeats}
    for label, workers, clock in (("all_cores_wall", None, time.perf_counter),
                                  ("one_worker_cpu", 1, time.process_time)):
        plain, strip = [], []
        for _ in range(repeats):
            tic = clock()
            il.bifurcation(PAPER, "omega", values, workers=workers, **kw)
            plain.append(clock() - tic)
            tic = clock()
            bif = il.bifurcation(PAPER, "omega", values, lyapunov=True, workers=workers, **kw)
            strip.append(clock() - tic)
        mp, ms = float(np.median(plain)), float(np.median(strip))
        out[label] = {"diagram_s": mp, "with_strip_s": ms, "overhead": ms / mp - 1.0}
    lam = bif.lyapunov
    out["chaotic_values"] = int(np.sum(lam > 0))
    out["sticking_values"] = int(np.sum(np.isneginf(lam)))
    return out


def bench_continuation(repeats):
    def both():
        up = il.continuation(PAPER, "omega", 5.0)
        down = il.continuation(PAPER, "omega", 1.0)
        return up, down
    res, (up, down) = timed(both, repeats)
    events = [(k, round(v, 6)) for k, v in down.events[::-1] + up.events]
    return {"omega_1_to_5_s": res, "points": len(up.param) + len(down.param),
            "events": events}


BEGIN, END = "<!-- bench_stability:begin -->", "<!-- bench_stability:end -->"


def markdown(out) -> str:
    o, s, c = out["orbit"], out["strip"], out["continuation"]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                            capture_output=True).stdout.strip() or "?"
    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    rows = [
        "## Stability and chaos (issue 8)",
        "",
        f"Written by `.venv/bin/python bench/bench_stability.py --write` on "
        f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC (commit {commit}; load "
        f"average at the end {load}). Medians after warm-up.",
        "",
        "| what | time | target |",
        "|---|---|---|",
        f"| `periodic_orbit`, period-1 with multipliers, Newton from a start on the section "
        f"| {o['from_start_s']['median'] * 1e3:.3f} ms ({o['iterations']} Newton steps) | < 1 ms |",
        f"| the same with the default start (one settling run from rest) "
        f"| {o['default_start_s']['median'] * 1e3:.3f} ms | |",
    ]
    for label, what in (("all_cores_wall", "wall time, all cores"),
                        ("one_worker_cpu", "CPU time, one worker")):
        f = s[label]
        rows.append(f"| {s['values']}-value ω diagram, {what}: without / with the Lyapunov strip "
                    f"| {f['diagram_s']:.3f} s / {f['with_strip_s']:.3f} s "
                    f"({100 * f['overhead']:+.0f}%) | <= +50% |")
    rows.append(f"| `continuation` over ω in [1, 5] (from ω = 2 both ways), with events "
                f"| {c['omega_1_to_5_s']['median'] * 1e3:.1f} ms ({c['points']} points) | < 1 s |")
    rows += ["", "Events found: " + ", ".join(f"{k} at ω = {v}" for k, v in c["events"]) + "."]
    return "\n".join([BEGIN] + rows + [END]) + "\n"


def write_section(text, begin=BEGIN, end=END, path=ROOT / "BENCHMARKS.md"):
    """Put ``text`` (which starts with ``begin`` and ends with ``end``) in place of the
    section between those markers in ``path``, or after the end of it."""
    old = path.read_text() if path.exists() else ""
    if begin in old and end in old:
        head, rest = old.split(begin, 1)
        new = head + text.rstrip("\n") + rest.split(end, 1)[1]
    else:
        new = old.rstrip("\n") + "\n\n" + text
    path.write_text(new)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--write", action="store_true", help="update its section of BENCHMARKS.md")
    a = ap.parse_args(argv)
    reps = 3 if a.quick else 7
    print(f"impactlib stability benchmark; {os.cpu_count()} cores; workers "
          f"{il.parallel.worker_count()}; repeats {reps} (medians after warm-up)")
    out = {"orbit": bench_orbit(reps), "strip": bench_strip(max(3, reps // 2)),
           "continuation": bench_continuation(reps)}
    o = out["orbit"]
    print(f"periodic_orbit, period-1 with multipliers, Newton from a start on the section: "
          f"{o['from_start_s']['median'] * 1e3:.3f} ms ({o['iterations']} Newton steps; "
          f"target < 1 ms); with the default settling start: "
          f"{o['default_start_s']['median'] * 1e3:.2f} ms")
    s = out["strip"]
    for label in ("all_cores_wall", "one_worker_cpu"):
        f = s[label]
        print(f"{s['values']}-value omega diagram [0.5, 5], t in [250, 500], {label}: "
              f"{f['diagram_s']:.3f} s; with the Lyapunov strip {f['with_strip_s']:.3f} s "
              f"(overhead {100 * f['overhead']:+.0f}%; target <= +50%)")
    print(f"  {s['chaotic_values']} values with lambda1 > 0, {s['sticking_values']} sticking")
    c = out["continuation"]
    print(f"continuation omega 2 -> 1 and 2 -> 5 with events: "
          f"{c['omega_1_to_5_s']['median'] * 1e3:.1f} ms ({c['points']} points; target < 1 s); "
          f"events {c['events']}")
    if a.json:
        a.json.write_text(json.dumps(out, indent=2))
    if a.write:
        write_section(markdown(out))


if __name__ == "__main__":
    main()
