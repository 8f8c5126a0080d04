"""The user's settings (one ``param.Parameterized``), their validation, and the URL.

``Settings`` holds what the user asked for, exactly as typed, including values that
are not physically valid: widgets write into it without ever raising. ``validate``
turns a settings snapshot into a frozen ``Run`` (what is computed) or a message that
names every bad field; the app then keeps the last good ``Run`` on screen.

The URL carries the whole state under the names in ``QUERY_NAMES``. ``psi`` in the
URL is the Poincare section in time units, as in the paper (0 <= psi <= T); the
settings hold it as a fraction of the period so that it follows omega.
"""
from __future__ import annotations

import dataclasses
import html
import math
from collections.abc import Mapping

import param

import impactlib as il

METHODS = ("exact", "rk4", "rk45")

#: Limits the app puts on top of the core's own validation, so that one session
#: cannot ask for unbounded work (the core adds its own impact/step ceilings).
T_END_MAX = 20_000.0
BIF_N_MAX = 2_000
OMEGA_MAX = 1_000.0


class Settings(param.Parameterized):
    """The user's settings. Defaults are the paper's (Lee, Fig. 2): m=1, c=0.05, k=1,
    g=0, r=0.8, omega=2, integrated to 500 s with the first 250 s discarded."""

    omega = param.Number(2.0, allow_None=True, softbounds=(0.05, 6.0), step=0.01,
                         label="ω  forcing frequency",
                         doc="Driving frequency ω of cos(ωτ) in rad/s; period T = 2π/ω.")
    r = param.Number(0.8, allow_None=True, softbounds=(0.0, 1.0), step=0.01,
                     label="r  restitution",
                     doc="Coefficient of restitution: ẋ(τ+) = −r ẋ(τ−) at the wall, 0 ≤ r ≤ 1.")
    c = param.Number(0.05, allow_None=True, softbounds=(0.0, 0.5), step=0.005,
                     label="c  damping",
                     doc="Damping c in m ẍ + 2c ẋ + k x = cos ωτ (c ≥ 0).")
    g = param.Number(0.0, allow_None=True, softbounds=(-1.0, 1.0), step=0.01,
                     label="g  endstop gap",
                     doc="Position of the rigid endstop; the mass moves in x ≥ g.")
    m = param.Number(1.0, allow_None=True, label="m  mass", doc="Mass m > 0.")
    k = param.Number(1.0, allow_None=True, label="k  stiffness", doc="Spring stiffness k ≥ 0.")
    psi = param.Number(0.0, allow_None=True, softbounds=(0.0, 1.0), step=0.005,
                       label="ψ/T  Poincaré section",
                       doc="Phase of the Poincaré section as a fraction of the period T: "
                           "the map samples (x, ẋ) at τ = ψ + nT.")
    t_end = param.Number(500.0, allow_None=True, label="total time (s)",
                         doc=f"End of the simulation, 0 < t_end ≤ {T_END_MAX:g} s.")
    t_record = param.Number(250.0, allow_None=True, label="discard transient (s)",
                            doc="Results are shown from this time on (0 ≤ t_record < t_end).")
    x0 = param.Number(None, allow_None=True, label="x₀  initial position",
                      doc="Initial position (≥ g); empty means at the wall, max(0, g).")
    v0 = param.Number(0.0, allow_None=True, label="v₀  initial velocity",
                      doc="Initial velocity ẋ(0).")
    method = param.Selector(default="exact", objects=list(METHODS), label="method",
                            doc="exact: closed-form flight with exact impact times; "
                                "rk4: fixed step dt; rk45: adaptive with rtol/atol.")
    dt = param.Number(1e-3, allow_None=True, label="rk4 step dt (s)",
                      doc="Fixed step of the rk4 method.")
    rtol = param.Number(1e-6, allow_None=True, label="rk45 rtol",
                        doc="Relative tolerance of the rk45 method (0 < rtol < 1).")
    atol = param.Number(1e-9, allow_None=True, label="rk45 atol",
                        doc="Absolute tolerance of the rk45 method (> 0).")
    bif_min = param.Number(0.1, allow_None=True, label="diagram ω from",
                           doc="Lowest ω of the bifurcation diagram (> 0).")
    bif_max = param.Number(5.0, allow_None=True, label="diagram ω to",
                           doc="Highest ω of the bifurcation diagram.")
    bif_n = param.Integer(400, allow_None=True, label="diagram values",
                          doc=f"Number of ω values in the diagram (2 … {BIF_N_MAX}).")


NUMBER_FIELDS = tuple(n for n in Settings.param if n not in ("name", "method"))
#: Every URL query name (all settings; psi in time units).
QUERY_NAMES = NUMBER_FIELDS + ("method",)
#: Settings whose change needs a new trajectory (the four scene views).
SCENE_FIELDS = frozenset(QUERY_NAMES) - {"psi", "bif_min", "bif_max", "bif_n"}
#: Settings the live bifurcation diagram depends on (it always uses the exact method).
DIAGRAM_FIELDS = frozenset({"m", "c", "k", "g", "r", "t_end", "t_record", "x0", "v0",
                            "bif_min", "bif_max", "bif_n"})


def defaults() -> dict:
    """Default value of every setting."""
    return {n: Settings.param[n].default for n in QUERY_NAMES}


def snapshot(settings: Settings) -> dict:
    return {n: getattr(settings, n) for n in QUERY_NAMES}


@dataclasses.dataclass(frozen=True)
class Run:
    """A validated, immutable description of what to compute (cache key material)."""

    params: il.Params
    t_end: float
    t_record: float
    x0: float | None
    v0: float
    method: str
    dt: float
    rtol: float
    atol: float
    psi_frac: float
    bif_min: float
    bif_max: float
    bif_n: int

    @property
    def psi(self) -> float:
        """Poincare section in time units, 0 <= psi <= T."""
        return self.psi_frac * self.params.T

    def sim_kwargs(self) -> dict:
        """Keyword arguments for ``il.simulate`` (without dense/phase)."""
        kw = dict(t_end=self.t_end, t_record=self.t_record, x0=self.x0, v0=self.v0,
                  method=self.method)
        if self.method == "rk4":
            kw["dt"] = self.dt
        elif self.method == "rk45":
            kw.update(rtol=self.rtol, atol=self.atol)
        return kw

    def scene_key(self) -> tuple:
        """What the trajectory depends on (not psi, not the diagram range)."""
        return (self.params, self.t_end, self.t_record, self.x0, self.v0, self.method,
                self.dt, self.rtol, self.atol)

    def diagram_key(self) -> tuple:
        p = self.params
        return (p.m, p.c, p.k, p.g, p.r, self.t_end, self.t_record, self.x0, self.v0,
                self.bif_min, self.bif_max, self.bif_n)


def _short(value) -> str:
    text = str(value)
    if len(text) > 24:
        text = text[:21] + "…"
    return html.escape(text)


def validate(values: Mapping) -> Run:
    """Turn raw settings into a ``Run``; raise ValueError naming every bad field."""
    errors: list[str] = []
    clean: dict = {}
    for name in NUMBER_FIELDS:
        v = values.get(name)
        if v is None:
            if name == "x0":
                clean[name] = None
                continue
            errors.append(f"{name}: a value is required")
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            errors.append(f"{name}: {_short(v)} is not a number")
            continue
        if not math.isfinite(v):
            errors.append(f"{name}: {_short(v)} is not a finite number")
            continue
        clean[name] = float(v)
    method = values.get("method")
    if method not in METHODS:
        errors.append(f"method: {_short(method)} is not one of {', '.join(METHODS)}")

    def need(cond: bool, field: str, text: str) -> None:
        if field in clean and not cond:
            errors.append(f"{field}: {text}")

    need(clean.get("omega", 1) <= OMEGA_MAX, "omega", f"must be ≤ {OMEGA_MAX:g}")
    need(0 < clean.get("t_end", 1) <= T_END_MAX, "t_end", f"must be in (0, {T_END_MAX:g}] s")
    if "t_end" in clean:
        need(0 <= clean.get("t_record", 0) < clean["t_end"], "t_record",
             "must be ≥ 0 and less than the total time")
    need(0 <= clean.get("psi", 0) <= 1, "psi", "the section must lie within one period [0, T]")
    need(clean.get("dt", 1) > 0, "dt", "must be > 0")
    need(0 < clean.get("rtol", 0.1) < 1, "rtol", "must be in (0, 1)")
    need(clean.get("atol", 1) > 0, "atol", "must be > 0")
    need(clean.get("bif_min", 1) > 0, "bif_min", "must be > 0")
    need(clean.get("bif_max", 1) <= OMEGA_MAX, "bif_max", f"must be ≤ {OMEGA_MAX:g}")
    if "bif_min" in clean:
        need(clean.get("bif_max", math.inf) > clean["bif_min"], "bif_max",
             "must be greater than the lowest ω")
    need(2 <= clean.get("bif_n", 2) <= BIF_N_MAX and float(clean.get("bif_n", 2)).is_integer(),
         "bif_n", f"must be a whole number in [2, {BIF_N_MAX}]")
    params = None
    phys = {n: clean[n] for n in il.PARAM_NAMES if n in clean}
    if len(phys) == len(il.PARAM_NAMES):
        try:
            params = il.Params(**phys)
        except (ValueError, TypeError) as exc:
            errors.append(html.escape(str(exc)))
    if "x0" in clean and clean["x0"] is not None and "g" in clean:
        need(clean["x0"] >= clean["g"], "x0", "must be ≥ g (the mass starts on the free side)")
    if errors or params is None:
        raise ValueError("; ".join(errors) or "invalid settings")
    return Run(params=params, t_end=clean["t_end"], t_record=clean["t_record"],
               x0=clean["x0"], v0=clean["v0"], method=method, dt=clean["dt"],
               rtol=clean["rtol"], atol=clean["atol"], psi_frac=clean["psi"],
               bif_min=clean["bif_min"], bif_max=clean["bif_max"], bif_n=int(clean["bif_n"]))


# -- URL ---------------------------------------------------------------------------

def parse_query(args: Mapping[str, object]) -> tuple[dict, list[str]]:
    """Settings from URL query arguments (str or bytes, or lists of them).

    Returns ``(values, errors)``: ``values`` holds every setting (bad or missing ones
    at their default, psi converted from time units to a fraction of the period) and
    ``errors`` one message per bad field. Never raises.
    """
    values = defaults()
    errors: list[str] = []
    raw: dict[str, str] = {}
    for name in QUERY_NAMES:
        if name not in args:
            continue
        v = args[name]
        if isinstance(v, (list, tuple)):
            v = v[-1] if v else ""
        if isinstance(v, bytes):
            v = v.decode("utf-8", "replace")
        raw[name] = str(v).strip()
    for name, text in raw.items():
        if name == "method":
            if text in METHODS:
                values[name] = text
            else:
                errors.append(f"method: {_short(text)} is not one of {', '.join(METHODS)}")
            continue
        if name == "x0" and text.lower() in ("", "none"):
            values[name] = None
            continue
        try:
            number = float(text)
        except ValueError:
            errors.append(f"{name}: {_short(text) or 'empty'} is not a number")
            continue
        if not math.isfinite(number):
            errors.append(f"{name}: {_short(text)} is not a finite number")
            continue
        if name == "bif_n":
            if not number.is_integer():
                errors.append(f"bif_n: {_short(text)} is not a whole number")
                continue
            number = int(number)
        values[name] = number
    # psi is in time units in the URL; the settings hold psi / T.
    if "psi" in raw and not any(e.startswith("psi:") for e in errors):
        omega = values["omega"]
        if isinstance(omega, float) and omega > 0:
            period = 2 * math.pi / omega
            psi = values["psi"]
            if 0 <= psi <= period * (1 + 1e-12):
                values["psi"] = min(psi / period, 1.0)
            else:
                errors.append(f"psi: {_short(raw['psi'])} lies outside one period "
                              f"[0, T = {period:.4g}]")
                values["psi"] = defaults()["psi"]
        else:
            values["psi"] = defaults()["psi"]
    return values, errors


def to_query(run: Run) -> dict[str, str]:
    """URL query arguments that restore ``run`` exactly (repr of floats round-trips)."""
    p = run.params
    q = {"omega": p.omega, "r": p.r, "c": p.c, "g": p.g, "m": p.m, "k": p.k,
         "psi": run.psi, "t_end": run.t_end, "t_record": run.t_record,
         "v0": run.v0, "method": run.method, "dt": run.dt, "rtol": run.rtol,
         "atol": run.atol, "bif_min": run.bif_min, "bif_max": run.bif_max,
         "bif_n": run.bif_n}
    if run.x0 is not None:
        q["x0"] = run.x0
    return {k: (v if isinstance(v, str) else repr(v)) for k, v in q.items()}


def settings_from_run(run: Run) -> dict:
    """Settings values that reproduce ``run``."""
    p = run.params
    return {"omega": p.omega, "r": p.r, "c": p.c, "g": p.g, "m": p.m, "k": p.k,
            "psi": run.psi_frac, "t_end": run.t_end, "t_record": run.t_record,
            "x0": run.x0, "v0": run.v0, "method": run.method, "dt": run.dt,
            "rtol": run.rtol, "atol": run.atol, "bif_min": run.bif_min,
            "bif_max": run.bif_max, "bif_n": run.bif_n}


def initial_settings(args: Mapping[str, object]) -> tuple[dict, list[str]]:
    """Settings for a new session from its URL: good fields kept, bad ones replaced by
    defaults; if the combination is still invalid, everything falls back to defaults."""
    values, errors = parse_query(args)
    try:
        validate(values)
    except ValueError as exc:
        errors.append(str(exc) + " — using the default settings")
        values = defaults()
    return values, errors
