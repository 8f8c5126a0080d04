"""Bad (and extreme) inputs at every entry point, and what each one gets.

One list of cases drives both the tests (tests/reliability/test_bad_input_*.py) and the
table in RELIABILITY.md (tests/reliability/make_table.py), so the table shows the
messages the code really gives. Each case runs once per process (cached).

Entry points:
- Python API: ``Params``, ``simulate``, ``bifurcation``, ``regime_map``;
- command line: ``python -m impactlib ...`` (subprocess);
- app URL: a new session built from query arguments as Tornado passes them (bytes);
- app widget: a value set on the session's real Panel widget, starting from a good scene.
The served app (over the websocket) is exercised in test_bad_input_app.py on top.
"""
from __future__ import annotations

import dataclasses
import functools
import html
import math
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
NAN, INF = math.nan, math.inf

#: A small diagram keeps the app cases quick (the diagram is not what they test).
SMALL = {"bif_n": "24", "bif_min": "0.5", "bif_max": "4"}
#: Work ceilings for API runs of valid-but-extreme inputs (so a case cannot hang).
API_CEILING = dict(max_steps=200_000, max_impacts=20_000)


@dataclasses.dataclass(frozen=True)
class Outcome:
    kind: str        # "rejected" | "runs" | "partial" | "crash"
    message: str     # what the caller sees (exception text, status message, app message)
    kept: bool = True      # app: the last good scene stayed on screen / a scene is shown


@dataclasses.dataclass(frozen=True)
class Case:
    entry: str                   # Params | simulate | bifurcation | regime_map | CLI | URL | widget
    tried: str                   # the input, as the table shows it
    fields: tuple[str, ...]      # names the message must mention; () for a valid input
    act: Callable[[], Outcome] = dataclasses.field(compare=False, repr=False)

    @property
    def id(self) -> str:
        return f"{self.entry}: {self.tried}"

    @property
    def expect(self) -> str:
        return "rejected" if self.fields else "runs"


def names_field(message: str, field: str) -> bool:
    """The message names ``field`` as a word (``m`` must not match inside ``omega``)."""
    return re.search(rf"(?<![A-Za-z_]){re.escape(field)}(?![A-Za-z_])", message) is not None


# -- Python API ----------------------------------------------------------------------

def _api(fn) -> Callable[[], Outcome]:
    def act():
        import impactlib as il

        try:
            out = fn(il)
        except ValueError as exc:
            return Outcome("rejected", str(exc))
        except Exception as exc:          # noqa: BLE001 - a crash is what the test reports
            return Outcome("crash", f"{type(exc).__name__}: {exc}")
        if isinstance(out, il.Solution):
            arrays = (out.impacts.t, out.impacts.v, out.poincare.x, out.poincare.v)
            finite = all(np.all(np.isfinite(a)) for a in arrays)
            label = il.classify(out).label
            text = (f"status {out.status}: {out.message}; motion: {label}"
                    + ("" if finite else "; NON-FINITE OUTPUT"))
            return Outcome("runs" if out.status == 0 else "partial", text, finite)
        if isinstance(out, il.Bifurcation):
            return Outcome("runs", f"{len(out)} impacts, status per value "
                                   f"{sorted(set(out.status.tolist()))}")
        return Outcome("runs", type(out).__name__)
    return act


def _params(**kw):
    shown = ", ".join(f"{k}={_show(v)}" for k, v in kw.items())
    return Case("Params", shown, tuple(kw), _api(lambda il: il.Params(**kw)))


def _show(v) -> str:
    if isinstance(v, float) and math.isnan(v):
        return "nan"
    if isinstance(v, str):
        return repr(v)
    return f"{v:g}" if isinstance(v, float) else repr(v)


def _sim(tried, fields, params=None, **kw):
    def run(il):
        return il.simulate(il.Params(**(params or {})), **{**API_CEILING, **kw})
    return Case("simulate", tried, fields, _api(run))


def api_cases() -> list[Case]:
    cases = [
        _params(m=NAN), _params(m=INF), _params(c=-INF), _params(k="abc"),
        _params(omega=""), _params(g=None), _params(r="0.5; import os"),
        _params(m=0.0), _params(m=-1.0), _params(k=-1.0), _params(c=-0.1),
        _params(r=-0.1), _params(r=1.5), _params(omega=0.0), _params(omega=-2.0),
        _params(m=1e-300), _params(c=1e300), _params(k=1e300),
        _params(m=-1.0, r=2.0, omega=NAN),
    ]
    cases += [
        _sim("Params(omega=1e12)", ("omega",), params=dict(omega=1e12)),
        _sim("Params(omega=1e12), t_record = t_end = 500", (), params=dict(omega=1e12),
             t_end=500.0, t_record=500.0),
        _sim("Params(g=1e6) (wall far above the motion)", (), params=dict(g=1e6)),
        _sim("Params(g=-1e6) (wall far below the motion)", (), params=dict(g=-1e6)),
        _sim("t_end=1e12", ("t_end",), t_end=1e12),
        _sim("t_end=1e12, t_record=1e12-100", (), t_end=1e12, t_record=1e12 - 100),
        _sim("t_end=nan", ("t_end",), t_end=NAN),
        _sim("t_end='500'", (), t_end="500"),
        _sim("t_end='abc'", ("t_end",), t_end="abc"),
        _sim("t_end=0", ("t_end",), t_end=0.0),
        _sim("t_record=600 > t_end=500", ("t_record",), t_record=600.0),
        _sim("t_record=-1", ("t_record",), t_record=-1.0),
        _sim("phase=-0.1 (psi before the period)", ("phase",), phase=-0.1),
        _sim("phase=T+1 (psi after the period)", ("phase",), phase=math.pi + 1),
        _sim("phase=inf", ("phase",), phase=INF),
        _sim("method='euler'", ("method",), method="euler"),
        _sim("method=''", ("method",), method=""),
        _sim("method='rk4', dt=10 (beyond RK4 stability)", ("dt",), method="rk4", dt=10.0),
        _sim("method='rk4', dt=0", ("dt",), method="rk4", dt=0.0),
        _sim("method='rk4', dt missing", ("dt",), method="rk4"),
        _sim("method='rk45', rtol=0", ("rtol",), method="rk45", rtol=0.0),
        _sim("method='rk45', atol=-1", ("atol",), method="rk45", atol=-1.0),
        _sim("x0=-1 with g=0 (behind the wall)", ("x0",), x0=-1.0),
        _sim("v0=nan", ("v0",), v0=NAN),
        _sim("dense=-1", ("dense",), dense=-1),
        _sim("dense=2.5", ("dense",), dense=2.5),
        _sim("t_end=nan, phase=-1, method='x' (three at once)", ("t_end", "phase", "method"),
             t_end=NAN, phase=-1.0, method="x"),
    ]
    bif = lambda **kw: (lambda il: il.bifurcation(il.Params(), **{**API_CEILING, **kw}))  # noqa: E731
    cases += [
        Case("bifurcation", "name='zeta'", ("zeta",), _api(bif(name="zeta", values=[1, 2]))),
        Case("bifurcation", "values=[1, nan]", ("omega",), _api(bif(name="omega", values=[1, NAN]))),
        Case("bifurcation", "values=[]", ("omega",), _api(bif(name="omega", values=[]))),
        Case("bifurcation", "values=['a']", ("omega",), _api(bif(name="omega", values=["a"]))),
        Case("bifurcation", "omega values=[0, 1]", ("omega",), _api(bif(name="omega", values=[0, 1]))),
        Case("bifurcation", "r values=[0.5, 1.5]", ("r",), _api(bif(name="r", values=[0.5, 1.5]))),
        Case("bifurcation", "t_end=1e12", ("t_end",), _api(bif(name="omega", values=[1, 2], t_end=1e12))),
        Case("bifurcation", "method='euler'", ("method",), _api(bif(name="omega", values=[1, 2], method="euler"))),
        Case("bifurcation", "method='rk4', dt=10", ("dt",),
             _api(bif(name="omega", values=[1, 2], method="rk4", dt=10.0))),
        Case("bifurcation", "warm_start='sideways'", ("warm_start",),
             _api(bif(name="omega", values=[1, 2], warm_start="sideways"))),
    ]
    rm = lambda **kw: (lambda il: il.regime_map(il.Params(), **{**API_CEILING, **kw}))  # noqa: E731
    cases += [
        Case("regime_map", "name_x = name_y = 'omega'", ("name_x",),
             _api(rm(name_x="omega", values_x=[1, 2], name_y="omega", values_y=[1, 2]))),
        Case("regime_map", "name_y='zeta'", ("zeta",),
             _api(rm(name_x="omega", values_x=[1, 2], name_y="zeta", values_y=[1, 2]))),
        Case("regime_map", "r values_y=[0.5, 2]", ("r",),
             _api(rm(name_x="omega", values_x=[1, 2], name_y="r", values_y=[0.5, 2.0]))),
        Case("regime_map", "values_x=[inf]", ("omega",),
             _api(rm(name_x="omega", values_x=[INF], name_y="r", values_y=[0.5]))),
        Case("regime_map", "t_end=1e12", ("t_end",),
             _api(rm(name_x="omega", values_x=[1, 2], name_y="r", values_y=[0.5], t_end=1e12))),
    ]
    return cases


# -- command line --------------------------------------------------------------------

def _cli(argv: list[str]) -> Callable[[], Outcome]:
    def act():
        proc = subprocess.run([sys.executable, "-m", "impactlib", *argv], cwd=ROOT,
                              capture_output=True, text=True, timeout=120)
        text = (proc.stderr.strip().splitlines() or proc.stdout.strip().splitlines() or [""])
        if "Traceback" in proc.stderr:
            return Outcome("crash", f"exit {proc.returncode}: {text[-1]}")
        kind = "rejected" if proc.returncode != 0 else "runs"
        return Outcome(kind, f"exit {proc.returncode}: {text[-1]}")
    return act


def cli_cases() -> list[Case]:
    """Bad arguments for each subcommand the command line has (found by introspecting
    its argparse parser, so new subcommands and options are covered as they appear)."""
    try:
        from impactlib import cli
    except ImportError:
        return []
    parser = cli.build_parser()
    cases = [Case("CLI", "(no command)", ("command",), _cli([])),
             Case("CLI", "frobnicate", ("frobnicate",), _cli(["frobnicate"]))]
    subs = {}
    for action in parser._actions:
        if action.__class__.__name__ == "_SubParsersAction":
            subs = action.choices
    bad_numbers = [("nan", "nan"), ("inf", "inf"), ("-inf", "-inf"), ("abc", "abc"),
                   ("''", "")]
    typed: set[str] = set()
    for name, sub in sorted(subs.items()):
        cases.append(Case("CLI", f"{name} --no-such-option", ("--no-such-option",),
                          _cli([name, "--no-such-option"])))
        for action in sub._actions:
            opt = next((o for o in action.option_strings if o.startswith("--")), None)
            if opt is None or action.nargs == 0:
                continue
            shared = getattr(action.type, "__name__", "") == "number"
            if action.type in (float, int) or shared or opt.lstrip("-") in (
                    "m", "c", "k", "g", "r", "omega", "t-end", "t_end", "t-record",
                    "t_record", "psi", "phase", "dt"):
                # options parsed by the one shared type (impactlib.commands.number) get
                # every bad value once per command, then one each (each case is a process)
                values = bad_numbers if not (shared and name in typed) else bad_numbers[:1]
                if shared:
                    typed.add(name)
                for shown, value in values:
                    cases.append(Case("CLI", f"{name} {opt} {shown}", (opt.lstrip("-"),),
                                      _cli([name, opt, value])))
    return cases


# -- app: URL and widgets --------------------------------------------------------------

def _seen(message: str) -> str:
    """The app's message as the reader sees it (it is HTML-escaped text)."""
    return html.unescape(message or "").strip()


def _badge(text: str) -> str:
    """The motion badge as the reader sees it (an HTML fragment)."""
    return html.unescape(re.sub(r"<[^>]+>", "", text or "")).strip()


@functools.cache
def _session():
    """One in-process app session shared by the widget cases (each case starts from the
    paper's defaults and restores them afterwards)."""
    from app.explorer import Explorer

    e = Explorer(args=dict(SMALL))
    e.diagram.job.cancel()
    return e


def _good_values():
    from app import state

    return {**state.defaults(), **{k: type(state.defaults()[k])(float(v)) for k, v in SMALL.items()}}


def _scene_data(e):
    return {v: getattr(e, v).source.data for v in ("displacement", "phase", "impact_map",
                                                     "poincare")}


def _widget(settings_changes: dict, widget_changes: dict) -> Callable[[], Outcome]:
    """Start from a good scene, apply ``settings_changes`` (valid context, e.g. method),
    then set each widget in ``widget_changes`` as the browser would set its value."""
    def act():
        e = _session()
        e.settings.param.update(**_good_values())
        e.diagram.job.cancel()
        if settings_changes:
            e.settings.param.update(**settings_changes)
            e.diagram.job.cancel()
        # a refusal's message stays until the next change; the widgets already show the
        # good values, so restoring them is no change: start each case without it
        e.controls.clear_message()
        assert e.message == "", e.message
        before = _scene_data(e)
        try:
            for name, value in widget_changes.items():
                e.widgets[name].value = value
        except Exception as exc:          # noqa: BLE001
            return Outcome("crash", f"{type(exc).__name__}: {exc}")
        finally:
            e.diagram.job.cancel()
        after = _scene_data(e)
        kept = all(after[v] is before[v] for v in before)
        msg = _seen(e.message)
        badge = _badge(e.badge.object)
        out = (Outcome("rejected", msg, kept) if msg else
               Outcome("runs", badge.split(" · computed")[0]
                       + (" ⚠ " + badge.split("⚠")[1].strip() if "⚠" in badge else ""),
                       True))
        e.settings.param.update(**_good_values())
        e.diagram.job.cancel()
        return out
    return act


def _url(args: dict) -> Callable[[], Outcome]:
    """A new session built from these query arguments (as bytes, the way Tornado gives
    them); the scene must be the defaults' (not blank)."""
    def act():
        from app.explorer import Explorer

        query = {**SMALL, **args}
        try:
            e = Explorer(args={k: [v.encode()] for k, v in query.items()})
        except Exception as exc:          # noqa: BLE001
            return Outcome("crash", f"{type(exc).__name__}: {exc}", False)
        e.diagram.job.cancel()
        shown = len(e.displacement.source.data.get("x", ())) > 0 and e.run is not None
        msg = _seen(e.message)
        if msg:
            return Outcome("rejected", msg, shown)
        badge = _badge(e.badge.object).split(" · computed")[0]
        return Outcome("runs", badge, shown)
    return act


def url_cases() -> list[Case]:
    q = lambda tried, fields, **args: Case("URL", tried, fields, _url(args))  # noqa: E731
    return [
        q("?omega=nan", ("omega",), omega="nan"),
        q("?m=inf", ("m",), m="inf"),
        q("?c=-inf", ("c",), c="-inf"),
        q("?k=abc", ("k",), k="abc"),
        q("?r= (empty)", ("r",), r=""),
        q("?m=0", ("m",), m="0"),
        q("?m=-1", ("m",), m="-1"),
        q("?k=-1", ("k",), k="-1"),
        q("?c=-0.1", ("c",), c="-0.1"),
        q("?r=-0.1", ("r",), r="-0.1"),
        q("?r=1.5", ("r",), r="1.5"),
        q("?omega=0", ("omega",), omega="0"),
        q("?omega=-2", ("omega",), omega="-2"),
        q("?omega=1e12", ("omega",), omega="1e12"),
        q("?g=1e6 (wall far above the motion)", (), g="1e6"),
        q("?g=-1e6 (wall far below the motion)", (), g="-1e6"),
        q("?t_end=1e12", ("t_end",), t_end="1e12"),
        q("?t_end=600&t_record=700", ("t_record",), t_end="600", t_record="700"),
        q("?psi=-0.1", ("psi",), psi="-0.1"),
        q("?psi=99 (beyond T = π)", ("psi",), psi="99"),
        q("?method=euler", ("method",), method="euler"),
        q("?method= (empty)", ("method",), method=""),
        q("?method=rk4&dt=10 (beyond RK4 stability)", ("dt",), method="rk4", dt="10"),
        q("?method=rk45&rtol=0", ("rtol",), method="rk45", rtol="0"),
        q("?x0=-1 (behind the wall g=0)", ("x0",), x0="-1"),
        q("?orbit_x0=0.5 (orbit_v0 missing)", ("orbit_v0",), orbit_x0="0.5"),
        q("?orbit_x0=-1&orbit_v0=0 (behind the wall g=0)", ("orbit_x0",), orbit_x0="-1",
          orbit_v0="0"),
        q("?orbit_x0=abc&orbit_v0=0", ("orbit_x0",), orbit_x0="abc", orbit_v0="0"),
        q("?bif_n=1e9", ("bif_n",), bif_n="1e9"),
        q("?m=1e-300", ("m",), m="1e-300"),
        q("?c=1e300", ("c",), c="1e300"),
        q("?m=__import__('os')", ("m",), m="__import__('os')"),
        q("?omega=../../etc/passwd", ("omega",), omega="../../etc/passwd"),
        q("?psi=<script>alert(1)</script>", ("psi",), psi="<script>alert(1)</script>"),
    ]


def widget_cases() -> list[Case]:
    w = lambda tried, fields, ctx=None, **vals: Case("widget", tried, fields,  # noqa: E731
                                                      _widget(ctx or {}, vals))
    return [
        w("m = nan", ("m",), m=NAN),
        w("k = inf", ("k",), k=INF),
        w("c = -inf", ("c",), c=-INF),
        w("m emptied (None)", ("m",), m=None),
        w("m = 0", ("m",), m=0.0),
        w("m = -1", ("m",), m=-1.0),
        w("k = -1", ("k",), k=-1.0),
        w("c = -0.1", ("c",), c=-0.1),
        w("r = -0.1", ("r",), r=-0.1),
        w("r = 1.5", ("r",), r=1.5),
        w("omega = 0", ("omega",), omega=0.0),
        w("omega = -1", ("omega",), omega=-1.0),
        w("omega = 1e12", ("omega",), omega=1e12),
        w("g = 1e6 (wall far above the motion)", (), g=1e6),
        w("g = -1e6 (wall far below the motion)", (), g=-1e6),
        w("t_end = 1e12", ("t_end",), t_end=1e12),
        w("t_record = 600 > t_end = 500", ("t_record",), t_record=600.0),
        w("psi/T = 1.5 (outside the period)", ("psi",), psi=1.5),
        w("psi/T = -0.5", ("psi",), psi=-0.5),
        w("dt = 10 with method rk4 (beyond stability)", ("dt",), {"method": "rk4"}, dt=10.0),
        w("rtol = 0 with method rk45", ("rtol",), {"method": "rk45"}, rtol=0.0),
        w("x0 = -1 (behind the wall g=0)", ("x0",), x0=-1.0),
        w("bif_n = 1000000", ("bif_n",), bif_n=1_000_000),
        w("m = 1e-300", ("m",), m=1e-300),
        w("c = 1e300", ("c",), c=1e300),
    ]


def all_cases() -> list[Case]:
    return api_cases() + cli_cases() + url_cases() + widget_cases()


@functools.cache
def outcome(case_id: str) -> Outcome:
    case = next(c for c in all_cases() if c.id == case_id)
    return case.act()
