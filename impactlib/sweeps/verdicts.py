"""classify()'s verdict on the cells of a regime map whose Poincare points never repeat:
chaotic, or a slow transient, or undetermined, by the Lyapunov criterion of
:mod:`impactlib.analysis.classify`, measured from where each cell's run ended.  The
measurements are the ones classify makes (measure_lyapunov), run as one jitted loop per
block of cells on the pool, and judged in Python.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..analysis.classify import classify, describe, judge_motion, lyapunov_budget
from ..analysis.lyapunov import WINDOWS as LYAPUNOV_WINDOWS
from ..analysis.lyapunov import lyapunov_result, lyapunov_rows, no_dissipation
from ..model import MotionCode, RunStatus
from ..parallel import interleaved, run_blocks
from ..simulate import simulate

# codes of classify's verdicts on aperiodic cells (RegimeMap)
_VERDICT_CODES = {
    "not settled": (MotionCode.NOT_SETTLED, MotionCode.INFINITE),
    "undetermined": (MotionCode.UNDETERMINED, MotionCode.UNDETERMINED),
    "unbounded": (MotionCode.UNBOUNDED, MotionCode.INFINITE),
}


#: what classify's verdict reads of a run (judge_motion), from a sweep's outputs
SweepRun = namedtuple("SweepRun", "params method t_end t_record final n_impacts nsteps")


def judge_aperiodic(p, name_x, vx, name_y, vy, impacts, period, finals, workers, **run_kw):
    """classify()'s verdict on the run (settings ``run_kw``) of each cell of a regime map
    whose points never repeated: whether it is chaotic is classify's call (one rule, the
    Lyapunov criterion), measured from where the sweep's run of the cell ended
    (``finals``, rows_kernel's, one row per cell).  The measurements are classify's
    (measure_lyapunov) made by one jitted loop per block of cells on the pool
    (:func:`measure_cells`).  Updates the codes in place; returns {(iy, ix): Motion}."""
    cells = np.argwhere((period == MotionCode.INFINITE) & (impacts != 0))
    nx = vx.size
    runs = {}
    motions = {}
    for iy, ix in cells:
        q = p.replace(**{name_x: float(vx[ix]), name_y: float(vy[iy])})
        if no_dissipation(q):
            # the growth check reads every impact of the window; the sweep kept a few
            motions[(int(iy), int(ix))] = classify(simulate(q, **run_kw))
            continue
        t, x, v, stuck, n_tot, nsteps = finals[iy * nx + ix].tolist()
        runs[(int(iy), int(ix))] = SweepRun(q, run_kw["method"], run_kw["t_end"],
                                            run_kw["t_record"], (t, x, v, stuck != 0.0),
                                            int(n_tot), int(nsteps))
    measured = measure_cells(list(runs.values()), workers)
    for (key, run), ly in zip(runs.items(), measured):
        motions[key] = judge_motion(describe(int(impacts[key]), int(period[key])), run,
                                    measured=ly)[0]
    motions = {(int(iy), int(ix)): motions[(int(iy), int(ix))] for iy, ix in cells}
    for (iy, ix), mo in motions.items():
        if mo.kind != "chaotic":
            impacts[iy, ix], period[iy, ix] = _VERDICT_CODES.get(
                mo.kind, _VERDICT_CODES["undetermined"])
    return motions


def measure_cells(runs, workers) -> list:
    """measure_lyapunov(run) for each of ``runs`` (SweepRun records of aperiodic motions):
    the same Lyapunov runs (lyapunov_rows: lyapunov_run's kernel run, impacts not kept)
    in blocks on the pool, and their results."""
    n = len(runs)
    if n == 0:
        return []
    rows = np.array([[r.params.m, r.params.c, r.params.k, r.params.g, r.params.r,
                      r.params.omega] for r in runs])
    starts = np.array([r.final[:3] for r in runs], dtype=np.float64)
    t_records = starts[:, 0].copy()
    t_ends = np.array([r.final[0] + (r.t_end - r.t_record) for r in runs], dtype=np.float64)
    limits = np.array([[b.max_impacts, b.max_steps] for b in map(lyapunov_budget, runs)],
                      dtype=np.float64)
    marks = np.array([np.linspace(a, b, LYAPUNOV_WINDOWS + 1) for a, b in zip(t_records, t_ends)])
    logs = np.zeros((n, LYAPUNOV_WINDOWS, 2))
    out = np.zeros((n, 7))

    def run_block(idx):
        lg = np.zeros((idx.size, LYAPUNOV_WINDOWS, 2))
        o = np.zeros((idx.size, 7))
        lyapunov_rows(rows[idx], starts[idx], t_ends[idx], t_records[idx], limits[idx],
                      marks[idx], lg, o)
        logs[idx] = lg
        out[idx] = o

    run_blocks(n, run_block, order=interleaved(n), max_block=64, workers=workers)
    none = np.empty(0)
    results = []
    for i, r in enumerate(runs):
        status = int(out[i, 0])
        if status == RunStatus.OUTPUT_FULL:
            status = RunStatus.OK
        final = (float(out[i, 3]), float(out[i, 4]), float(out[i, 5]), out[i, 6] != 0.0)
        results.append(lyapunov_result(r.params, float(t_ends[i]), float(t_records[i]), logs[i],
                                       marks[i], status, out[i, 1] != 0.0, int(out[i, 2]),
                                       none, none, final))
    return results
