"""The accuracy report: error against run time of exact, rk4 and rk45 against independent
references (cases, runs, tables and a plot).

Needs the optional extra ``report`` (mpmath for the reference, matplotlib for the plot):
``pip install impact-explorer[report]``; the command asks for it by name when missing.
Impact matching and the error metrics are :mod:`impactlib.compare`.


``python -m impactlib accuracy [--quick] [--out DIR]`` runs :func:`main`.  For each case
(the paper's defaults and the stiff and extreme cases of issue 2) and each method setting
(exact; rk4 over a range of dt; rk45 over a range of rtol), it compares the impacts in
[0, t_end] with the mpmath reference of :mod:`impactlib.reference` and reports

* the largest error in impact time (absolute) and in impact velocity (relative to the
  largest impact speed of the case),
* missed and extra impacts (matched by time, within half the gap to the neighbouring
  reference impacts),
* for chattering cases, the error in the accumulation time where the mass comes to rest
  (the chatter's impacts below 1e-4 of the largest speed are compared through it, not one
  by one: the solver sums that geometric tail, the reference steps through it),
* the run time: median of repeated ``simulate`` calls after a warm-up (``time.perf_counter``).

The scipy ``solve_ivp`` reference is run too, where it applies, as a cross-check of the
mpmath reference (one row per case); where it does not (chatter, sticking, shallow dips)
the row says so.
"""
from __future__ import annotations

import math
import os
import platform
import time
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from .compare import V_FLOOR, Comparison, impact_errors, match_impacts  # noqa: F401 (re-exported)
from ..model import Params, rk4_stability_limit
from .reference import ReferenceNotApplicable, ivp_impacts, mp_impacts, mp_state
from ..simulate import simulate

PAPER = Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)
DENSE = 200


def steady_orbit(p: Params):
    """Start exactly on the steady forced orbit x_p(t) = P cos(wt) + Q sin(wt) at t = 0.

    Returns (x0, v0, A) with A = 1 / sqrt(D) its amplitude: x_p has minimum -A.
    """
    det = p.k - p.m * p.omega ** 2
    d = det * det + (2.0 * p.c * p.omega) ** 2
    P = det / d
    Q = 2.0 * p.c * p.omega / d
    return P, p.omega * Q, 1.0 / math.sqrt(d)


_GX0, _GV0, _GA = steady_orbit(PAPER)


@dataclass(frozen=True)
class Case:
    """One accuracy case: parameters, start and horizon [0, t_end]."""

    name: str
    title: str
    params: Params
    t_end: float
    x0: float | None = None
    v0: float = 0.0
    dense: bool = False          # compare the trajectory (no impacts expected)
    quick: bool = False          # part of --quick
    note: str = ""


CASES = (
    Case("paper", "paper defaults (omega=2, r=0.8, c=0.05)", PAPER, 40.0, quick=True),
    Case("stiff", "stiff k=1e4, slow forcing omega=1", PAPER.replace(k=1e4, omega=1.0), 2.5,
         quick=True, note="near-grazing impacts from rest, then chatter and sticking"),
    Case("tiny-m", "tiny mass m=1e-4 (overdamped)", PAPER.replace(m=1e-4), 1.0,
         note="chatter, then sticking"),
    Case("c=2", "heavy damping c=2", PAPER.replace(c=2.0), 20.0),
    Case("c=5", "heavy damping c=5", PAPER.replace(c=5.0), 4.0, note="chatter, sticking"),
    Case("critical", "critical damping c=sqrt(km)=1", PAPER.replace(c=1.0), 20.0, quick=True),
    Case("crit+1e-9", "near-critical c=1+1e-9", PAPER.replace(c=1.0 + 1e-9), 20.0),
    Case("crit-1e-9", "near-critical c=1-1e-9", PAPER.replace(c=1.0 - 1e-9), 20.0),
    Case("resonance", "exact resonance c=0, omega=1, no contact (g=-1000)",
         PAPER.replace(c=0.0, omega=1.0, g=-1000.0), 100.0, dense=True, quick=True,
         note="x = t sin(t)/2; trajectory compared at 200 samples"),
    Case("res-contact", "exact resonance c=0, omega=1, wall at g=-5",
         PAPER.replace(c=0.0, omega=1.0, g=-5.0), 40.0),
    Case("r=0", "plastic r=0", PAPER.replace(r=0.0), 20.0, note="sticks after every impact"),
    Case("r=1,c=0", "elastic r=1, undamped c=0 (energy check)", PAPER.replace(r=1.0, c=0.0), 40.0,
         note="impact energy grows (impact resonance omega=2 omega_n): speed error = energy error"),
    Case("omega=0.01", "slow forcing omega=0.01", PAPER.replace(omega=0.01), 170.0,
         note="chatter and sticking"),
    Case("omega=0.2", "paper scene omega=0.2 (complete chattering)", PAPER.replace(omega=0.2), 25.0,
         quick=True, note="chatter, sticking, release"),
    Case("omega=20", "fast forcing omega=20", PAPER.replace(omega=20.0), 20.0),
    Case("gap", "gap g=-0.5", PAPER.replace(g=-0.5), 15.0),
    Case("preload 0.3", "preload g=0.3", PAPER.replace(g=0.3), 20.0),
    Case("preload 0.5", "preload g=0.5", PAPER.replace(g=0.5), 12.0,
         note="its transient amplifies rounding ~10x per impact after t~20 (see tests)"),
    Case("grazing", "grazing: steady orbit dips 1e-10*A below the wall",
         PAPER.replace(g=-_GA * (1.0 - 1e-10)), 20.0, x0=_GX0, v0=_GV0, quick=True,
         note="first impact speed ~1e-5; its error is amplified (~a*eps*A/|v|)"),
    Case("near miss", "near miss: steady orbit clears the wall by 1e-6*A",
         PAPER.replace(g=-_GA * (1.0 + 1e-6)), 60.0, x0=_GX0, v0=_GV0, quick=True,
         note="no impact"),
)

CASE_BY_NAME = {c.name: c for c in CASES}


@lru_cache(maxsize=None)
def reference(case: Case):
    """mpmath reference impacts of a case on [0, t_end] (cached for the session)."""
    return mp_impacts(case.params, 1_000_000, x0=case.x0, v0=case.v0, t_max=case.t_end)


@lru_cache(maxsize=None)
def dense_reference(case: Case):
    ts = np.linspace(0.0, case.t_end, DENSE)
    x, v = mp_state(case.params, ts, x0=case.x0, v0=case.v0)
    return ts, x, v


@lru_cache(maxsize=None)
def ivp_reference(case: Case):
    """solve_ivp impacts of a case, or the reason it does not apply (a string)."""
    try:
        return ivp_impacts(case.params, 1_000_000, x0=case.x0, v0=case.v0, t_max=case.t_end)
    except ReferenceNotApplicable as err:
        return str(err)


# ------------------------------------------------------------------ comparison


def compare(case: Case, sol, ref=None) -> Comparison:
    """Compare a Solution run over [0, case.t_end] with the case's mpmath reference."""
    ref = reference(case) if ref is None else ref
    out = impact_errors(ref.t, ref.v, sol.impacts.t, sol.impacts.v, V_FLOOR)
    if case.dense:
        ts, xr, vr = dense_reference(case)
        d = sol.dense
        out.err_state = float(max(np.max(np.abs(d.x - xr)), np.max(np.abs(d.v - vr))))
    if ref.sticking:
        starts = np.array([s for s, _ in ref.sticking])
        mine = sol.sticking[:, 0] if sol.sticking.size else np.empty(0)
        if mine.size == 0:
            out.err_stick = math.inf
        else:
            errs = [np.min(np.abs(mine - s)) for s in starts]
            out.err_stick = float(np.max(errs))
    return out


# ------------------------------------------------------------------ runs


@dataclass(frozen=True)
class Setting:
    method: str
    value: float | None = None      # dt (rk4) or rtol (rk45)

    @property
    def label(self):
        if self.method == "exact":
            return "exact"
        if self.method == "rk4":
            return f"rk4 dt={self.value:g}"
        return f"rk45 rtol={self.value:g}"

    def kwargs(self):
        if self.method == "rk4":
            return {"method": "rk4", "dt": self.value}
        if self.method == "rk45":
            return {"method": "rk45", "rtol": self.value, "atol": 1e-3 * self.value}
        return {"method": "exact"}


FULL_SETTINGS = ((Setting("exact"),)
                 + tuple(Setting("rk4", dt) for dt in (1e-1, 1e-2, 1e-3, 1e-4))
                 + tuple(Setting("rk45", rt) for rt in (1e-3, 1e-6, 1e-9, 1e-12)))
QUICK_SETTINGS = (Setting("exact"), Setting("rk4", 1e-2), Setting("rk4", 1e-3),
                  Setting("rk45", 1e-6), Setting("rk45", 1e-10))


@dataclass
class Row:
    case: Case
    setting: Setting | None          # None: the solve_ivp cross-check row
    cmp: Comparison | None = None
    seconds: float = math.nan
    error: str = ""                  # ValueError message (e.g. rk4 beyond stability)
    status: str = ""


def run_case(case: Case, setting: Setting, repeats: int = 5, budget: float = 1.0):
    """Solution of one case and setting, and the median run time of ``simulate``."""
    kw = setting.kwargs()
    call = dict(t_end=case.t_end, t_record=0.0, x0=case.x0, v0=case.v0,
                dense=DENSE if case.dense else 0, **kw)
    sol = simulate(case.params, **call)          # warm-up (compilation / cache load)
    times = []
    spent = 0.0
    for _ in range(repeats):
        tic = time.perf_counter()
        sol = simulate(case.params, **call)
        dt = time.perf_counter() - tic
        times.append(dt)
        spent += dt
        if spent > budget and len(times) >= 1:
            break
    return sol, float(np.median(times))


def evaluate(case: Case, setting: Setting, repeats: int = 5) -> Row:
    try:
        sol, sec = run_case(case, setting, repeats)
    except ValueError as err:
        return Row(case, setting, error=str(err))
    row = Row(case, setting, compare(case, sol), sec)
    if not sol.success:
        row.status = sol.message
    return row


def ivp_row(case: Case) -> Row:
    """The solve_ivp reference against the mpmath reference (a cross-check)."""
    ivp = ivp_reference(case)
    if isinstance(ivp, str):
        return Row(case, None, error="not applicable: " + ivp.replace("solve_ivp reference: ", ""))
    ref = reference(case)
    out = impact_errors(ref.t, ref.v, ivp.t, ivp.v, V_FLOOR)
    return Row(case, None, out)


def work_precision(cases=CASES, settings=FULL_SETTINGS, repeats=5, progress=None):
    rows = []
    for case in cases:
        reference(case)
        if case.dense:
            dense_reference(case)
        rows.append(ivp_row(case))
        for s in settings:
            rows.append(evaluate(case, s, repeats))
            if progress:
                progress(rows[-1])
    return rows


# ------------------------------------------------------------------ output


def _e(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    if math.isinf(x):
        return "none"
    return f"{x:.1e}"


def row_cells(row: Row):
    method = row.setting.label if row.setting else "ref: solve_ivp"
    if row.error:
        msg = row.error
        if "stability limit" in msg:
            msg = "ValueError: " + msg[msg.index("dt="):]
        return [row.case.name, method, "", "", "", "", "", "", "", msg]
    c = row.cmp
    ms = "" if math.isnan(row.seconds) else f"{1e3 * row.seconds:.3g}"
    note = []
    if c.tail:
        note.append(f"{c.tail} slow tail impacts summed")
    if row.status:
        note.append(row.status)
    state = "" if math.isnan(c.err_state) else _e(c.err_state)
    return [row.case.name, method, str(c.compared), _e(c.err_t) if c.compared else "—",
            _e(c.err_v) if c.compared else "—", str(c.missed), str(c.extra),
            _e(c.err_stick) if not math.isnan(c.err_stick) else state, ms, "; ".join(note)]


HEADER = ["case", "method", "impacts", "max|Δt|", "max|Δv|/V", "missed", "extra",
          "Δt_stick / Δstate", "ms", "notes"]


def text_table(rows) -> str:
    cells = [HEADER] + [row_cells(r) for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(HEADER) - 1)]
    lines = []
    for c in cells:
        lines.append("  ".join(s.ljust(w) for s, w in zip(c, widths)) + "  " + c[-1])
    return "\n".join(lines)


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import numba
    import scipy
    import mpmath
    return (f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"numpy {np.__version__}, numba {numba.__version__}, scipy {scipy.__version__}, "
            f"mpmath {mpmath.__version__}")


def markdown(rows, quick: bool, png_name: str) -> str:
    lines = [
        "# Accuracy: error against run time",
        "",
        "Generated by `python -m impactlib accuracy" + (" --quick" if quick else "") + "` "
        f"on {machine()}.",
        "",
        "Every method is compared with an independent reference: the closed form evaluated in",
        "mpmath at 40 digits, impacts bracketed on a dense grid with every turning point",
        "checked and refined by safeguarded Newton (`impactlib/verify/reference.py`). The row",
        "`ref: solve_ivp` cross-checks that reference with scipy's DOP853 (rtol 1e-12) and a",
        "terminal event, where it applies (not through chatter, sticking or shallow dips).",
        "",
        "Columns: impacts compared one by one over [0, t_end] from the case's start; the largest",
        "error in impact time and in impact velocity (relative to the largest impact speed V);",
        "impacts the method missed or added; for chattering cases the error in the time the",
        "chatter ends on the wall (impacts slower than 1e-4 V are summed by the solver and",
        "compared through that time), or for the no-contact case the largest state error at",
        "200 samples; the median run time of one `simulate` call after a warm-up. rk4 steps",
        "beyond the stability limit give the ValueError shown instead of numbers.",
        "",
        f"![work-precision]({png_name})",
        "",
        "## Summary",
        "",
        "Per case: the exact method's largest errors and run time; for rk4 and rk45 the most",
        "accurate setting run and, in brackets, how many settings missed or added impacts.",
        "",
        "| case | exact max\\|Δt\\| | exact max\\|Δv\\|/V | exact ms | best rk4 (max\\|Δt\\| @ ms) "
        "| best rk45 (max\\|Δt\\| @ ms) | solve_ivp cross-check |",
        "|---|---|---|---|---|---|---|",
    ] + summary_lines(rows) + ["", "## All rows", ""]
    by_case = {}
    for r in rows:
        by_case.setdefault(r.case, []).append(r)
    for case, rs in by_case.items():
        lines.append(f"### {case.name}: {case.title}")
        lines.append("")
        desc = f"t in [0, {case.t_end:g}]"
        if case.x0 is not None:
            desc += f", start x0={case.x0:.17g}, v0={case.v0:.17g} (on the steady orbit)"
        if case.note:
            desc += f"; {case.note}"
        lines.append(desc + ".")
        lines.append("")
        lines.append("| " + " | ".join(h.replace("|", "\\|") for h in HEADER) + " |")
        lines.append("|" + "---|" * len(HEADER))
        for r in rs:
            lines.append("| " + " | ".join(c.replace("|", "\\|") for c in row_cells(r)) + " |")
        lines.append("")
    return "\n".join(lines)


def summary_lines(rows):
    by_case = {}
    for r in rows:
        by_case.setdefault(r.case, []).append(r)
    out = []
    for case, rs in by_case.items():
        cells = [case.name]
        ex = next(r for r in rs if r.setting and r.setting.method == "exact")
        c = ex.cmp
        if case.dense:
            cells += [f"state {_e(c.err_state)}", "—"]
        elif c.compared:
            cells += [_e(c.err_t), _e(c.err_v)]
        else:
            cells += [f"no impact ({c.extra} extra)", "—"]
        cells.append(f"{1e3 * ex.seconds:.3g}")
        for method in ("rk4", "rk45"):
            mine = [r for r in rs if r.setting and r.setting.method == method]
            ok = [r for r in mine if not r.error]
            bad = sum(1 for r in ok if r.cmp.missed or r.cmp.extra)
            unstable = sum(1 for r in mine if r.error)

            def err(r):
                return r.cmp.err_state if case.dense else (r.cmp.err_t if r.cmp.compared
                                                           else math.inf)
            good = [r for r in ok if not (r.cmp.missed or r.cmp.extra)]
            if good and not all(math.isinf(err(r)) for r in good):
                b = min(good, key=err)
                txt = f"{_e(err(b))} @ {1e3 * b.seconds:.3g} ({b.setting.label.split()[-1]})"
            elif good:
                txt = "no impact (all agree)"
            else:
                txt = "every setting wrong"
            extra = []
            if bad:
                extra.append(f"{bad} missed/added")
            if unstable:
                extra.append(f"{unstable} unstable dt")
            cells.append(txt + (f" [{', '.join(extra)}]" if extra else ""))
        ivp = next(r for r in rs if r.setting is None)
        if ivp.error:
            cells.append(ivp.error)
        elif ivp.cmp.missed:
            cells.append(f"misses {ivp.cmp.missed} impacts")
        elif ivp.cmp.compared:
            cells.append(f"agrees to {_e(max(ivp.cmp.err_t, ivp.cmp.err_v))}")
        else:
            cells.append("no impact")
        out.append("| " + " | ".join(cells) + " |")
    return out


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    cases = []
    for r in rows:
        if r.case not in cases:
            cases.append(r.case)
    ncol = 4
    nrow = math.ceil(len(cases) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4 * ncol, 3.2 * nrow), squeeze=False)
    style = {"exact": ("*", "C3"), "rk4": ("o-", "C0"), "rk45": ("s-", "C2")}
    floor = 1e-17
    for ax, case in zip(axes.flat, cases):
        notes = []
        for method in ("rk4", "rk45", "exact"):
            rs = [r for r in rows if r.case is case and r.setting and r.setting.method == method
                  and not r.error]
            if not rs:
                continue
            x, y = [], []
            for r in rs:
                c = r.cmp
                if case.dense:
                    err = c.err_state
                elif c.compared:
                    err = c.err_t
                else:
                    err = math.nan
                if c.missed or c.extra:
                    notes.append(f"{r.setting.label}: {c.missed} missed, {c.extra} extra")
                if not math.isnan(err):
                    x.append(1e3 * r.seconds)
                    y.append(max(err, floor))
            mk, col = style[method]
            if x:
                ax.loglog(x, y, mk, color=col, label=method, ms=9 if method == "exact" else 5)
        if notes:
            ax.text(0.02, 0.02, "\n".join(notes[:6]), transform=ax.transAxes, fontsize=5.5,
                    va="bottom")
        if not ax.lines:
            ax.text(0.5, 0.6, "no impact in [0, t_end]" if not notes else "", ha="center",
                    transform=ax.transAxes, fontsize=8)
        ax.set_title(case.name + (" (state error)" if case.dense else ""), fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_minor_formatter(NullFormatter())
    for ax in list(axes.flat)[len(cases):]:
        ax.axis("off")
    axes[0, 0].legend(fontsize=7)
    fig.supxlabel("run time of one simulate() call [ms]")
    fig.supylabel("max |impact time error|  (0 drawn at 1e-17)")
    fig.suptitle("Work-precision: exact vs rk4 (dt) and rk45 (rtol), against the mpmath reference")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(quick: bool = False, out: str | os.PathLike | None = None, echo=print) -> int:
    out = Path(out) if out is not None else Path.cwd()
    out.mkdir(parents=True, exist_ok=True)
    cases = [c for c in CASES if c.quick] if quick else list(CASES)
    settings = QUICK_SETTINGS if quick else FULL_SETTINGS
    repeats = 3 if quick else 7
    tic = time.perf_counter()
    rows = work_precision(cases, settings, repeats)
    table = text_table(rows)
    echo(table)
    png = out / "accuracy.png"
    md = out / "BENCHMARKS-accuracy.md"
    plot(rows, png)
    md.write_text(markdown(rows, quick, png.name) + "\n")
    echo(f"\nwrote {md} and {png} ({time.perf_counter() - tic:.0f} s)")
    return 0


__all__ = ["CASES", "CASE_BY_NAME", "Case", "Comparison", "Setting", "compare", "match_impacts",
           "reference", "ivp_reference", "dense_reference", "steady_orbit", "work_precision",
           "main", "rk4_stability_limit"]
