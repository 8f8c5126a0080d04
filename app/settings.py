"""Every setting of the app, described once; everything else is derived from ``SETTINGS``.

A ``Setting`` holds a name (also its URL query name), label, default, valid range,
help text, the widget that edits it, and which results depend on it:

- ``scene``: the trajectory, i.e. the four scene views (and the diagram marker);
- ``section``: the Poincaré map only;
- ``diagram``: the bifurcation diagram (except the parameter it sweeps, which only moves
  its marker; see ``state.Run.diagram_key``).

Settings of the research views (group ``RESEARCH``: regime map, basins) affect nothing
that is computed automatically: those views compute on demand.

``orbit_x0``, ``orbit_v0`` (both or neither) start the scene alone on a periodic orbit,
recorded from t = 0; the diagram and the maps keep ``x0``, ``v0``, ``t_record``
(``state.Run.scene_start``).

A setting that affects none of them switches an extra result on or off (``branches``:
the branch overlay, computed from the finished diagram; a ``flag``, 1 or 0 in the URL).

A ``display`` setting (``presenter``) travels in the URL but is not part of a ``Run``
and never causes a computation.

Derived here: the ``Settings`` class (one ``param.Parameterized`` holding what the user
typed, valid or not), ``QUERY_NAMES``, ``SCENE_FIELDS``, ``SECTION_FIELDS``,
``DIAGRAM_FIELDS``, and the method options passed to ``impactlib.simulate``
(``method_options``). Physical ranges come from ``impactlib.FIELDS``.

Adding a setting: append one ``Setting`` (and a field to ``Run`` appears by itself);
if it is a new argument of a computation, pass it there.
"""
from __future__ import annotations

import dataclasses

import param

import impactlib as il

#: Limits the app puts on top of the core's own validation, so that one session
#: cannot ask for unbounded work (the core adds its own impact/step ceilings).
T_END_MAX = 20_000.0
BIF_N_MAX = 2_000
OMEGA_MAX = 1_000.0
#: Cells per side of the regime map and of the basins picture.
MAP_N_MAX = 300
BASINS_N_MAX = 200

#: Parameters a diagram or a regime map can sweep (il.Params fields), and the range
#: swept when none is given: the paper's for omega (Fig. 3) and r (Fig. 3 a-f), around
#: the paper's values for the others.
SWEEPABLE = ("omega", "r", "c", "g", "m", "k")
SWEEP_RANGES = {"omega": (0.1, 5.0), "r": (0.0, 1.0), "c": (0.0, 0.5), "g": (-1.0, 1.0),
                "m": (0.25, 4.0), "k": (0.0, 4.0)}
#: Diagram sweep modes (URL ``bif_sweep``) -> ``il.bifurcation(warm_start=)``.
SWEEP_MODES = {"independent": False, "up": "up", "down": "down", "both": "both"}
#: Symbols and axis labels of the sweepable parameters.
SYMBOLS = {"omega": "ω", "r": "r", "c": "c", "g": "g", "m": "m", "k": "k"}
AXIS_LABELS = {"omega": "driving frequency ω (rad/s)", "r": "restitution r",
               "c": "damping c", "g": "endstop gap g", "m": "mass m", "k": "stiffness k"}

SCENE, SECTION, DIAGRAM = "scene", "section", "diagram"
#: The page's modes (URL ``mode``), one plot area each (app.controls).
MODES = ("explore", "compare", "research")
#: Group of the research settings: shown in research mode, not in the settings drawer.
RESEARCH = "Research"
#: Group of the settings shown above the diagram (not in the sidebar): its overlays.
ON_DIAGRAM = "On the diagram"


@dataclasses.dataclass(frozen=True)
class Setting:
    name: str                     # attribute, URL query name and simulate() keyword
    label: str
    default: object
    doc: str
    affects: frozenset            # results that depend on it (SCENE, SECTION, DIAGRAM)
    group: str                    # the settings drawer's card
    widget: str = "input"         # "slider" | "input" | "select" | "checkbox" | "toggle" | "radio"
    kind: str = "number"          # "number" | "integer" | "choice" | "flag" (on/off)
    lo: float | None = None       # valid range; None: unbounded
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    range_text: str = ""          # message for a value out of range, if not the default one
    soft: tuple | None = None     # slider range
    step: float | None = None
    fmt: str | None = None        # numbro format of the input box
    half: bool = False            # half a row (two inputs side by side)
    optional: bool = False        # empty (None) is a valid value
    choices: tuple = ()
    method: str | None = None     # used by this integration method only
    physical: bool = False        # an il.Params field (the core checks its own range)
    display: bool = False         # only changes how results are shown (not part of a Run)


    @property
    def decimals(self) -> int | None:
        """Decimal places of the widget's step (values are rounded to the step)."""
        if self.step is None:
            return None
        return max(0, -int(f"{self.step:e}".split("e")[1]))

    @property
    def out_of_range(self) -> str:
        """What a value outside [lo, hi] is told."""
        if self.range_text:
            return self.range_text
        lo, hi = self.lo, self.hi
        whole = "a whole number " if self.kind == "integer" else ""
        if lo is not None and hi is not None:
            return (f"must be {whole}in {'(' if self.lo_open else '['}{lo:g}, {hi:g}"
                    f"{')' if self.hi_open else ']'}{' ' + self.unit if self.unit else ''}")
        if lo is not None:
            return f"must be {'>' if self.lo_open else '≥'} {lo:g}"
        return f"must be {'<' if self.hi_open else '≤'} {hi:g}"


def _physical(name: str, label: str, default: float, doc: str, **kw) -> Setting:
    """A physical parameter: its valid range is the core's (``impactlib.FIELDS``)."""
    f = il.FIELDS[name]
    return Setting(name, label, default, doc, frozenset({SCENE, SECTION}) | kw.pop("diagram"),
                   "Physics", lo=f.lo, hi=kw.pop("hi", f.hi), lo_open=f.lo_open,
                   physical=True, **kw)


_TRAJECTORY = frozenset({SCENE, SECTION})
_EVERYTHING = frozenset({SCENE, SECTION, DIAGRAM})

#: The settings, in sidebar order. Defaults are the paper's (Lee, Fig. 2): m=1, c=0.05,
#: k=1, g=0, r=0.8, omega=2, integrated to 500 s with the first 250 s discarded.
SETTINGS: tuple[Setting, ...] = (
    _physical("omega", "ω  forcing frequency", 2.0,
              "Driving frequency ω of cos(ωτ) in rad/s; period T = 2π/ω.",
              diagram=frozenset({DIAGRAM}),
              hi=OMEGA_MAX, widget="slider", soft=(0.05, 6.0), step=0.01, fmt="0.000"),
    _physical("r", "r  restitution", 0.8,
              "Coefficient of restitution: ẋ(τ+) = −r ẋ(τ−) at the wall, 0 ≤ r ≤ 1.",
              diagram=frozenset({DIAGRAM}), widget="slider",
              soft=(il.FIELDS["r"].lo, il.FIELDS["r"].hi), step=0.01, fmt="0.000"),
    _physical("c", "c  damping", 0.05, "Damping c in m ẍ + 2c ẋ + k x = cos ωτ (c ≥ 0).",
              diagram=frozenset({DIAGRAM}), widget="slider",
              soft=(il.FIELDS["c"].lo, 0.5), step=0.005, fmt="0.000"),
    _physical("g", "g  endstop gap", 0.0,
              "Position of the rigid endstop; the mass moves in x ≥ g.",
              diagram=frozenset({DIAGRAM}), widget="slider", soft=(-1.0, 1.0), step=0.01,
              fmt="0.000"),
    _physical("m", "m  mass", 1.0, "Mass m > 0.", diagram=frozenset({DIAGRAM}), half=True),
    _physical("k", "k  stiffness", 1.0, "Spring stiffness k ≥ 0.", diagram=frozenset({DIAGRAM}),
              half=True),
    Setting("psi", "ψ/T  Poincaré section", 0.0,
            "Phase of the Poincaré section as a fraction of the period T: the map samples "
            "(x, ẋ) at τ = ψ + nT.", frozenset({SECTION}), "Poincaré section",
            widget="slider", lo=0.0, hi=1.0, soft=(0.0, 1.0), step=0.005, fmt="0.000",
            range_text="the section must lie within one period [0, T]"),
    Setting("t_end", "total time (s)", 500.0,
            f"End of the simulation, 0 < t_end ≤ {T_END_MAX:g} s.", _EVERYTHING,
            "Time window, start, method", lo=0.0, lo_open=True, hi=T_END_MAX, unit="s",
            half=True),
    Setting("t_record", "discard transient (s)", 250.0,
            "Results are shown from this time on (0 ≤ t_record < t_end).", _EVERYTHING,
            "Time window, start, method", half=True),
    Setting("x0", "x₀  initial position", None,
            "Initial position (≥ g); empty means at the wall, max(0, g).", _EVERYTHING,
            "Time window, start, method", half=True, optional=True),
    Setting("v0", "v₀  initial velocity", 0.0, "Initial velocity ẋ(0).", _EVERYTHING,
            "Time window, start, method", half=True),
    Setting("orbit_x0", "orbit x₀  on a periodic orbit", None,
            "The scene starts on a periodic orbit (a tap on a branch or a boundary curve): "
            "its state (x, ẋ) at t = 0, run with no transient discarded. Empty: the scene "
            "starts at (x₀, v₀) and discards the transient, as the diagram and the maps "
            "do (they never use these two).", _TRAJECTORY, "Time window, start, method",
            half=True, optional=True),
    Setting("orbit_v0", "orbit v₀  on a periodic orbit", None,
            "Velocity of the periodic orbit's state at t = 0 (with orbit_x0).", _TRAJECTORY,
            "Time window, start, method", half=True, optional=True),
    Setting("method", "method", "exact",
            "exact: closed-form flight with exact impact times; rk4: fixed step dt; "
            "rk45: adaptive with rtol/atol.", _TRAJECTORY, "Time window, start, method",
            widget="select", kind="choice", choices=tuple(il.METHODS)),
    Setting("dt", "rk4 step dt (s)", 1e-3, "Fixed step of the rk4 method.", _TRAJECTORY,
            "Time window, start, method", lo=0.0, lo_open=True, fmt="0.[000000]",
            method="rk4"),
    Setting("rtol", "rk45 rtol", 1e-6, "Relative tolerance of the rk45 method (0 < rtol < 1).",
            _TRAJECTORY, "Time window, start, method", lo=0.0, hi=1.0, lo_open=True,
            hi_open=True, fmt="0.[0000000000]", half=True, method="rk45"),
    Setting("atol", "rk45 atol", 1e-9, "Absolute tolerance of the rk45 method (> 0).",
            _TRAJECTORY, "Time window, start, method", lo=0.0, lo_open=True,
            fmt="0.[000000000000]", half=True, method="rk45"),
    Setting("bif_param", "diagram parameter", "omega",
            "The parameter the bifurcation diagram sweeps (the others stay as set).",
            frozenset({DIAGRAM}), "Bifurcation diagram range", widget="select",
            kind="choice", choices=SWEEPABLE),
    Setting("bif_sweep", "sweep mode", "independent",
            "independent: every value starts from (x₀, v₀); up / down: each value starts "
            "where the previous (lower / higher) one ended, which shows hysteresis; both: "
            "up and down in two colours.", frozenset({DIAGRAM}), "Bifurcation diagram range",
            widget="select", kind="choice", choices=tuple(SWEEP_MODES)),
    Setting("bif_min", "diagram from", 0.1,
            "Lowest value of the swept parameter; empty: the default range of that "
            "parameter.", frozenset({DIAGRAM}), "Bifurcation diagram range", half=True,
            optional=True),
    Setting("bif_max", "diagram to", 5.0,
            "Highest value of the swept parameter; empty: the default range of that "
            "parameter.", frozenset({DIAGRAM}), "Bifurcation diagram range", half=True,
            optional=True),
    Setting("bif_n", "diagram values", 400,
            f"Number of values in the diagram (2 … {BIF_N_MAX}).", frozenset({DIAGRAM}),
            "Bifurcation diagram range", kind="integer", lo=2, hi=BIF_N_MAX),
    Setting("branches", "periodic branches on the diagram", False,
            "Continue the periodic orbits the diagram finds over its range: stable parts "
            "solid, unstable dashed, bifurcations and grazings marked (URL: branches=1).",
            frozenset(), ON_DIAGRAM, widget="checkbox", kind="flag"),
    Setting("map_x", "regime map x", "omega", "Parameter along the regime map's x axis.",
            frozenset(), RESEARCH, widget="select", kind="choice", choices=SWEEPABLE,
            half=True),
    Setting("map_y", "regime map y", "r", "Parameter along the regime map's y axis.",
            frozenset(), RESEARCH, widget="select", kind="choice", choices=SWEEPABLE,
            half=True),
    Setting("map_n", "regime map cells per side", 100,
            f"Grid of the regime map: n × n cells (2 … {MAP_N_MAX}).", frozenset(), RESEARCH,
            kind="integer", lo=2, hi=MAP_N_MAX, half=True),
    Setting("boundaries", "boundary curves", False,
            "Period-doubling, saddle-node and grazing curves of the periodic orbits in the "
            "regime map's box, followed from the branches at the map's y value "
            "(impactlib.boundary); drawn over the map (URL: boundaries=1).", frozenset(),
            RESEARCH, widget="checkbox", kind="flag"),
    Setting("basins_n", "basins cells per side", 100,
            f"Grid of the basins picture: n × n starts (2 … {BASINS_N_MAX}).", frozenset(),
            RESEARCH, kind="integer", lo=2, hi=BASINS_N_MAX, half=True),
    Setting("mode", "mode", "explore",
            "What the page shows: explore (the scene's views and the diagram), compare "
            "(the paper's Fig. 3 and Fig. 7 side by side) or research (regime map, basins).",
            frozenset(), "header", widget="radio", kind="choice", choices=MODES, display=True),
    Setting("presenter", "Presenter", False,
            "Large type and thick lines for a projector (read from the back of the room).",
            frozenset(), "header", widget="toggle", kind="flag", display=True),
)

BY_NAME = {s.name: s for s in SETTINGS}
#: Every URL query name, in the order of SETTINGS.
QUERY_NAMES = tuple(s.name for s in SETTINGS)
NUMBER_FIELDS = tuple(s.name for s in SETTINGS if s.kind in ("number", "integer"))
FLAG_FIELDS = tuple(s.name for s in SETTINGS if s.kind == "flag" and not s.display)
CHOICE_FIELDS = tuple(s.name for s in SETTINGS if s.kind == "choice")
#: Settings that only change how results are shown (not part of a Run).
DISPLAY_FIELDS = tuple(s.name for s in SETTINGS if s.display)
#: Significant digits of a number in a URL (and of every value computed with).
URL_DIGITS = 10
SCENE_FIELDS = frozenset(s.name for s in SETTINGS if SCENE in s.affects)
SECTION_FIELDS = frozenset(s.name for s in SETTINGS if SECTION in s.affects)
DIAGRAM_FIELDS = frozenset(s.name for s in SETTINGS if DIAGRAM in s.affects)
#: Settings that are not il.Params fields (a Run holds them next to its Params).
RUN_FIELDS = tuple(s.name for s in SETTINGS if not s.physical and not s.display)
METHODS = BY_NAME["method"].choices


def method_options(values, method: str) -> dict:
    """The method's own simulate() options (rk4: dt; rk45: rtol, atol) from ``values``
    (any object with the settings as attributes)."""
    return {s.name: getattr(values, s.name) for s in SETTINGS if s.method == method}


def method_text(values, method: str) -> str:
    """The method's options as the accuracy table shows them ("dt = 0.001")."""
    opts = method_options(values, method)
    return ", ".join(f"{k} = {v:g}" for k, v in opts.items()) or "closed form"


def _parameter(s: Setting) -> param.Parameter:
    common = dict(label=s.label, doc=s.doc)
    if s.kind == "flag":
        return param.Boolean(default=s.default, **common)
    if s.kind == "choice":
        return param.Selector(default=s.default, objects=list(s.choices), **common)
    cls = param.Integer if s.kind == "integer" else param.Number
    extra = {"softbounds": s.soft} if s.soft else {}
    if s.step is not None:
        extra["step"] = s.step
    return cls(s.default, allow_None=True, **common, **extra)


#: The user's settings as typed (bad values included: widgets never raise on them).
Settings = type("Settings", (param.Parameterized,),
                {"__doc__": "The user's settings; see app.settings.SETTINGS.",
                 "__module__": __name__, **{s.name: _parameter(s) for s in SETTINGS}})
