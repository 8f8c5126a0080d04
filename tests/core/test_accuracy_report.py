"""The accuracy report: its matching logic, and the command end to end (--quick)."""
import subprocess
import sys

import numpy as np

from impactlib import cli
from impactlib.verify.compare import match_impacts
from impactlib.verify.report import CASES


def test_match_counts_missed_extra_and_tail():
    ref_t = np.array([1.0, 2.0, 3.0, 3.001, 3.0015])
    ref_v = np.array([-1.0, -1.0, -0.5, -1e-6, -1e-7])     # last two: slow chatter tail
    t = np.array([1.0 + 1e-9, 2.6, 3.0 - 1e-9])              # 2.0 missed, 2.6 extra
    v = np.array([-1.0, -0.8, -0.5])
    pairs, missed, extra, tail = match_impacts(ref_t, ref_v, t, v, v_floor=1e-4)
    assert pairs == [(0, 0), (2, 2)]
    assert (missed, extra, tail) == (1, 1, 2)


def test_cases_cover_the_issue():
    names = {c.name for c in CASES}
    for must in ("paper", "stiff", "tiny-m", "c=2", "c=5", "critical", "crit+1e-9", "crit-1e-9",
                 "resonance", "r=0", "r=1,c=0", "omega=0.01", "omega=20", "gap", "preload 0.3",
                 "preload 0.5", "grazing", "near miss"):
        assert must in names


def test_accuracy_command_quick(tmp_path):
    lines = []
    from impactlib.verify import report
    assert report.main(quick=True, out=tmp_path, echo=lines.append) == 0
    text = "\n".join(lines)
    assert "exact" in text and "rk4 dt=0.01" in text and "rk45 rtol=1e-06" in text
    md = (tmp_path / "BENCHMARKS-accuracy.md").read_text()
    assert "| grazing | exact | 4 |" in md
    assert "not applicable: chatter" in md               # where solve_ivp cannot follow
    png = (tmp_path / "accuracy.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_cli_wiring():
    args = cli.build_parser().parse_args(["accuracy", "--quick", "--out", "x"])
    assert (args.command, args.quick, args.out) == ("accuracy", True, "x")
    out = subprocess.run([sys.executable, "-m", "impactlib", "accuracy", "--help"],
                         capture_output=True, text=True, check=True, timeout=120)
    assert "--quick" in out.stdout and "--out" in out.stdout


def test_accuracy_command_names_the_missing_extra():
    """Without mpmath (the report's reference) the command says which extra to install,
    and the core and the metrics the app uses still import."""
    code = ("import sys; sys.modules['mpmath'] = None; "
            "import impactlib, impactlib.verify.compare; from impactlib.cli import main; "
            "sys.exit(main(['accuracy', '--quick', '--out', 'unused']))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 2, out.stderr
    assert "impact-explorer[report]" in out.stderr and "mpmath" in out.stderr
