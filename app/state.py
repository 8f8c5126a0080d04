"""From what the user typed to what is computed: validation, the frozen ``Run``, the URL.

``Settings`` (app.settings) holds what the user asked for, exactly as typed, including
values that are not valid: widgets write into it without ever raising. ``validate``
turns a settings snapshot into a frozen ``Run`` (what is computed) or a message that
names every bad field; the app then keeps the last good ``Run`` on screen.

The URL carries the whole state under the names in ``QUERY_NAMES``. ``psi`` in the
URL is the Poincare section in time units, as in the paper (0 <= psi <= T); the
settings hold it as a fraction of the period so that it follows omega. ``scene``
names the paper's scene the settings came from (its values are the base; numbers in
the URL override them).

Numbers are rounded before they are computed with: to the widget's step where it has
one (a slider that sends 4.2299999999999995 computes 4.23), else to ``URL_DIGITS``
significant digits; psi (a fraction of T in the widget, time in the URL) to the
step grid, or else to the fraction that a ``URL_DIGITS``-digit time gives back. So the URL the app writes (at
most ``URL_DIGITS`` significant digits) gives back exactly the same ``Run``, and the
same scene data.
"""
from __future__ import annotations

import dataclasses
import functools
import html
import math
from collections.abc import Mapping

import impactlib as il

from .scenes import BY_KEY as SCENES_BY_KEY
from .settings import (BY_NAME, CHOICE_FIELDS, DIAGRAM_FIELDS, DISPLAY_FIELDS, FLAG_FIELDS,
                       METHODS, NUMBER_FIELDS, OMEGA_MAX, QUERY_NAMES, RUN_FIELDS, SCENE_FIELDS,
                       SETTINGS, SWEEP_RANGES, SYMBOLS, URL_DIGITS, Settings)

#: URL name of the paper's scene the settings came from.
SCENE_NAME = "scene"
_TRUE, _FALSE = ("1", "true", "yes", "on"), ("0", "false", "no", "off", "")

__all__ = ["DISPLAY_FIELDS", "METHODS", "QUERY_NAMES", "Run", "Settings", "SettingsError",
           "applied", "base_run", "base_settings", "defaults", "differences", "from_query",
           "initial_settings", "parse_query", "scene_of", "snapshot", "to_query", "validate"]


def defaults() -> dict:
    """Default value of every setting."""
    return {s.name: s.default for s in SETTINGS}


def snapshot(settings: Settings) -> dict:
    return {n: getattr(settings, n) for n in QUERY_NAMES}


def _psi(self) -> float:
    """Poincare section in time units, 0 <= psi <= T (the setting is psi / T)."""
    return self.psi_frac * self.params.T


def _key(self, fields: frozenset) -> tuple:
    """(name, value) of the settings in ``fields``, physical ones from ``params``, the
    method's own options only for that method."""
    out = []
    for s in SETTINGS:
        if s.name in fields and (s.method is None or s.method == self.method):
            out.append((s.name, getattr(self.params if s.physical else self, s.name)))
    return tuple(out)


#: Settings that start the scene alone on a periodic orbit (see ``_scene_start``), and
#: the settings whose change leaves that orbit (the session then empties them).
ORBIT_FIELDS = frozenset({"orbit_x0", "orbit_v0"})
LEAVES_ORBIT = frozenset(il.PARAM_NAMES) | {"x0", "v0", "t_record"}


def _scene_start(self) -> tuple:
    """(x0, v0, t_record) of the scene: on the periodic orbit from t = 0 when
    ``orbit_x0`` and ``orbit_v0`` are set, else the start and window of the diagram."""
    if self.orbit_x0 is not None:
        return self.orbit_x0, self.orbit_v0, 0.0
    return self.x0, self.v0, self.t_record


def _scene_key(self) -> tuple:
    """What the trajectory depends on: Params, then the run options as (name, value)
    pairs named as ``il.simulate`` keywords (not psi, not the diagram range; the start
    and window are the scene's own, ``scene_start``)."""
    start = dict(zip(("x0", "v0", "t_record"), self.scene_start))
    pairs = _key(self, SCENE_FIELDS - {n for n in il.PARAM_NAMES} - ORBIT_FIELDS)
    return (self.params,) + tuple((n, start.get(n, v)) for n, v in pairs)


def _diagram_key(self) -> tuple:
    """What the bifurcation diagram depends on: everything in DIAGRAM_FIELDS (the swept
    parameter's name and the sweep mode included) but the swept parameter's current
    value, which only moves the marker."""
    return _key(self, DIAGRAM_FIELDS - {self.bif_param})


def _field(name: str) -> str:
    return "psi_frac" if name == "psi" else name


#: A validated, immutable description of what to compute (cache key material): ``params``
#: (il.Params) and one field per other setting (``psi_frac`` for psi, a fraction of T).
Run = dataclasses.make_dataclass(
    "Run", [("params", il.Params)] + [(_field(n), object) for n in RUN_FIELDS], frozen=True,
    namespace={"psi": property(_psi), "scene_start": property(_scene_start),
               "scene_key": _scene_key, "diagram_key": _diagram_key,
               "__module__": __name__})


def _short(value) -> str:
    text = str(value)
    if len(text) > 24:
        text = text[:21] + "…"
    return html.escape(text)


def _in_range(s, x: float) -> bool:
    """``x`` within the setting's range (a physical one's is the core's, with the app's
    ceiling on top where the core has none)."""
    if s.lo is not None and (x <= s.lo if s.lo_open else x < s.lo):
        return False
    if s.hi is not None and (x >= s.hi if s.hi_open else x > s.hi):
        return False
    return s.kind != "integer" or float(x).is_integer()


def significant(x: float, digits: int = URL_DIGITS) -> float:
    """``x`` rounded to ``digits`` significant digits."""
    return float(f"{x:.{digits}g}")


def rounded(s, x: float) -> float:
    """``x`` as computed with: on the widget's step grid (if that keeps it within the
    setting's range), else to ``URL_DIGITS`` significant digits."""
    if s.decimals is not None:
        on_grid = round(x, s.decimals)
        above = s.lo is None or (on_grid > s.lo if s.lo_open else on_grid >= s.lo)
        below = s.hi is None or (on_grid < s.hi if s.hi_open else on_grid <= s.hi)
        if above and below:
            return on_grid
    return significant(x)


def holds(widget_value, value) -> bool:
    """A widget holding ``widget_value`` already shows ``value``: equal, or floats apart
    by rounding noise only (a slider's keyboard steps add up to 2.0199999999999996).
    Writing such a value back would move a slider the user is still moving."""
    if isinstance(widget_value, float) and isinstance(value, float):
        return math.isclose(widget_value, value, rel_tol=1e-12, abs_tol=1e-15)
    return widget_value == value


class SettingsError(ValueError):
    """Settings that cannot be computed; ``fields`` holds the names of the bad ones."""

    def __init__(self, message: str, fields: frozenset):
        super().__init__(message)
        self.fields = fields


def validate(values: Mapping) -> Run:
    """Turn raw settings into a ``Run``; raise SettingsError naming every bad field, its
    value and what is allowed."""
    errors: list[str] = []
    clean: dict = {}
    for name in NUMBER_FIELDS:
        s, v = BY_NAME[name], values.get(name)
        if v is None:
            if s.optional:
                clean[name] = None
            else:
                errors.append(f"{name}: a value is required")
        elif isinstance(v, bool) or not isinstance(v, (int, float)):
            errors.append(f"{name}: {_short(v)} is not a number")
        elif not math.isfinite(v):
            errors.append(f"{name}: {_short(v)} is not a finite number")
        elif not _in_range(s, v):
            errors.append(f"{name}: {v:g} — {s.out_of_range}")
            clean[name] = float(v)          # still usable by the checks between fields
        else:
            clean[name] = float(v) if name == "psi" else rounded(s, float(v))
    for name in FLAG_FIELDS:
        v = values.get(name, False)
        if isinstance(v, bool):
            clean[name] = v
        else:
            errors.append(f"{name}: {_short(v)} is not on or off")
    for name in CHOICE_FIELDS:
        choices, v = BY_NAME[name].choices, values.get(name)
        if v in choices:
            clean[name] = v
        else:
            errors.append(f"{name}: {_short(v)} is not one of {', '.join(choices)}")

    def need(cond: bool, field: str, text: str) -> None:
        if field in clean and not cond and not any(e.startswith(field + ":") for e in errors):
            errors.append(f"{field}: {text}")

    if "t_end" in clean:
        need(0 <= clean.get("t_record", 0) < clean["t_end"], "t_record",
             f"{clean.get('t_record', 0):g} — must be ≥ 0 and less than the total time "
             f"({clean['t_end']:g} s)")
    _check_sweep_range(clean, errors)
    if ("orbit_x0" in clean and "orbit_v0" in clean
            and (clean["orbit_x0"] is None) != (clean["orbit_v0"] is None)):
        empty = "orbit_x0" if clean["orbit_x0"] is None else "orbit_v0"
        errors.append(f"{empty}: empty — orbit_x0 and orbit_v0 go together (both set, or "
                      "both empty)")
    if clean.get("orbit_x0") is not None and clean.get("g") is not None:
        need(clean["orbit_x0"] >= clean["g"], "orbit_x0",
             f"{clean['orbit_x0']:g} — must be ≥ g = {clean['g']:g} (the orbit's state "
             "lies on the free side)")
    if "map_x" in clean and "map_y" in clean:
        need(clean["map_x"] != clean["map_y"], "map_y",
             f"{clean['map_y']} — must be another parameter than map_x")
    if clean.get("x0") is not None and clean.get("g") is not None:
        need(clean["x0"] >= clean["g"], "x0", f"{clean['x0']:g} — must be ≥ g = {clean['g']:g} "
             "(the mass starts on the free side)")
    params = None
    phys = {n: clean[n] for n in il.PARAM_NAMES if n in clean}
    if len(phys) == len(il.PARAM_NAMES) and not _named(errors) & set(il.PARAM_NAMES):
        try:
            params = il.Params(**phys)
        except (ValueError, TypeError) as exc:
            errors.append(html.escape(str(exc)))
    if errors or params is None:
        raise SettingsError("; ".join(errors) or "invalid settings", _named(errors))
    clean["psi"] = psi_fraction(clean["psi"], params.T)
    rest = {_field(n): clean[n] for n in RUN_FIELDS}
    for name in ("bif_n", "map_n", "basins_n"):
        rest[name] = int(rest[name])
    return Run(params=params, **rest)


def _named(errors: list[str]) -> frozenset:
    """The settings named in ``errors`` ("name: ..." or the core's "name=value")."""
    names = set()
    for e in errors:
        head = e.split(":", 1)[0].strip()
        if head in BY_NAME:
            names.add(head)
        names.update(n for n in il.PARAM_NAMES if f"{n}=" in e)
    return frozenset(names)


def applied(run: Run) -> dict:
    """The settings, as the widgets hold them, that give ``run`` (psi as a fraction of
    the period, an empty diagram range resolved): what the page shows once it is
    applied."""
    out = {}
    for s in SETTINGS:
        if s.display:
            continue
        out[s.name] = (getattr(run.params, s.name) if s.physical else
                       run.psi_frac if s.name == "psi" else getattr(run, s.name))
    return out


def _check_sweep_range(clean: dict, errors: list) -> None:
    """Resolve an empty diagram range to the swept parameter's default range and check
    both ends against that parameter's physical range (messages name bif_min/bif_max)."""
    name = clean.get("bif_param")
    if name is None or any(e.startswith(("bif_min:", "bif_max:")) for e in errors):
        return
    lo_default, hi_default = SWEEP_RANGES[name]
    lo = clean["bif_min"] if clean.get("bif_min") is not None else lo_default
    hi = clean["bif_max"] if clean.get("bif_max") is not None else hi_default
    clean["bif_min"], clean["bif_max"] = lo, hi
    f, sym = il.FIELDS[name], SYMBOLS[name]
    top = OMEGA_MAX if name == "omega" else f.hi
    for field, v in (("bif_min", lo), ("bif_max", hi)):
        low = f.lo is not None and (v <= f.lo if f.lo_open else v < f.lo)
        if low or (top is not None and v > top):
            left = "(-∞" if f.lo is None else f"{'(' if f.lo_open else '['}{f.lo:g}"
            span = f"{left}, {'∞)' if top is None else f'{top:g}]'}"
            errors.append(f"{field}: {v:g} is outside the range of {sym}, {span}")
    if not any(e.startswith(("bif_min:", "bif_max:")) for e in errors) and not hi > lo:
        errors.append(f"bif_max: {hi:g} — must be greater than the lowest {sym} ({lo:g})")
    if name == "g" and clean.get("x0") is not None and clean["x0"] < hi:
        errors.append(f"x0: {clean['x0']:g} — must be ≥ the largest g of the diagram "
                      f"({hi:g}), or empty (at the wall)")


# -- URL ---------------------------------------------------------------------------

def psi_fraction(frac: float, period: float) -> float:
    """The section's fraction of the period as computed with. psi travels in time units
    (``URL_DIGITS`` digits), so the fraction is the one such a time gives back, exactly
    as ``parse_query`` computes it; within 1e-9 of the slider's step grid it is the
    grid value (a scene's 1/8 stays 0.125)."""
    frac = min(significant(frac * period) / period, 1.0)
    on_grid = round(frac, BY_NAME["psi"].decimals)
    return on_grid if abs(frac - on_grid) <= 1e-9 else frac


def scene_of(args: Mapping[str, object]) -> str | None:
    """The scene key named in the URL (``scene=fig5``), or None."""
    v = args.get(SCENE_NAME)
    if isinstance(v, (list, tuple)):
        v = v[-1] if v else ""
    if isinstance(v, bytes):
        v = v.decode("utf-8", "replace")
    v = str(v or "").strip()
    return v if v in SCENES_BY_KEY else None


def parse_query(args: Mapping[str, object]) -> tuple[dict, list[str]]:
    """Settings from URL query arguments (str or bytes, or lists of them).

    Returns ``(values, errors)``: ``values`` holds every setting (bad or missing ones
    at their default, psi converted from time units to a fraction of the period) and
    ``errors`` one message per bad field. Never raises.
    """
    scene = scene_of(args)
    values = {**defaults(), **(SCENES_BY_KEY[scene].settings() if scene else {})}
    errors: list[str] = []
    if scene is None and str(args.get(SCENE_NAME) or "").strip() not in ("", "[]"):
        errors.append(f"scene: {_short(args.get(SCENE_NAME))} is not a scene of the paper")
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
        s = BY_NAME[name]
        if s.kind == "flag":
            if text.lower() in _TRUE + _FALSE:
                values[name] = text.lower() in _TRUE
            else:
                errors.append(f"{name}: {_short(text)} is not 1 or 0")
            continue
        if s.kind == "choice":
            if text in s.choices:
                values[name] = text
            else:
                errors.append(f"{name}: {_short(text)} is not one of {', '.join(s.choices)}")
            continue
        if s.optional and text.lower() in ("", "none"):
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
        if s.kind == "integer":
            if not number.is_integer():
                errors.append(f"{name}: {_short(text)} is not a whole number")
                continue
            number = int(number)
        values[name] = number
    # A link that picks the swept parameter without a range gets that parameter's range.
    if "bif_param" in raw and values["bif_param"] != "omega":
        for name in ("bif_min", "bif_max"):
            if name not in raw:
                values[name] = None
    # psi is in time units in the URL; the settings hold psi / T.
    if "psi" in raw and not any(e.startswith("psi:") for e in errors):
        omega = values["omega"]
        if isinstance(omega, float) and omega > 0:
            period = 2 * math.pi / omega
            psi = values["psi"]
            if 0 <= psi <= period * (1 + 10.0 ** -(URL_DIGITS - 1)):
                values["psi"] = min(psi / period, 1.0)
            else:
                errors.append(f"psi: {_short(raw['psi'])} lies outside one period "
                              f"[0, T = {period:.4g}]")
                values["psi"] = defaults()["psi"]
        else:
            values["psi"] = defaults()["psi"]
    return values, errors


def url_number(v) -> str:
    """Shortest text that gives back ``v`` (a validated value has at most URL_DIGITS
    significant digits; psi in time units is cut there and rounds back on parsing)."""
    text = repr(v)
    digits = len(text.split("e")[0].replace("-", "").replace(".", "").lstrip("0"))
    return text if digits <= URL_DIGITS else f"{v:.{URL_DIGITS}g}"


def base_settings(scene: str | None) -> dict:
    """The settings a page starts from: the paper's defaults, or a scene's."""
    return {**defaults(), **(SCENES_BY_KEY[scene].settings() if scene else {})}


@functools.lru_cache(maxsize=None)
def base_run(scene: str | None) -> Run:
    """The ``Run`` of ``base_settings(scene)``."""
    return validate(base_settings(scene))


def differences(run: Run, scene: str | None) -> dict:
    """Settings of ``run`` (URL names, values as ``applied`` gives them) that differ
    from those of the scene (or the defaults) and change what is computed (not the
    research settings, not the branch overlay)."""
    now, base = applied(run), applied(base_run(scene))
    return {s.name: now[s.name] for s in SETTINGS
            if not s.display and s.affects and now[s.name] != base[s.name]}


def to_query(run: Run, scene: str | None = None, display: Mapping | None = None) -> dict[str, str]:
    """URL query arguments that restore ``run`` exactly: the scene it came from and the
    settings that differ from that scene (without a scene, every setting), and the
    display settings that are not at their default."""
    q = {SCENE_NAME: scene} if scene else {}
    now = applied(run)
    base = applied(base_run(scene)) if scene else None
    for s in SETTINGS:
        if s.display:
            v = (display or {}).get(s.name, s.default)
            if v != s.default:
                q[s.name] = ("1" if v else "0") if s.kind == "flag" else str(v)
            continue
        if base is not None and now[s.name] == base[s.name] and not (
                s.name in ("bif_min", "bif_max") and now["bif_param"] != base["bif_param"]):
            continue                # (a link naming another parameter gets its own range)
        v = (getattr(run.params, s.name) if s.physical else
             run.psi if s.name == "psi" else getattr(run, s.name))
        if isinstance(v, bool):
            q[s.name] = "1" if v else "0"
        elif v is not None:
            q[s.name] = v if isinstance(v, str) else url_number(v)
        elif base is not None:
            q[s.name] = ""                  # emptied (x0 at the wall) where the scene has one
    return q


#: Settings checked together: a refusal of the first may be the other's doing.
_RELATED = {"t_record": ("t_end",), "bif_max": ("bif_min", "bif_param"),
            "bif_min": ("bif_param",), "x0": ("g", "bif_max"), "map_y": ("map_x",),
            "orbit_x0": ("g", "orbit_v0"), "orbit_v0": ("orbit_x0",)}


def from_query(args: Mapping[str, object]) -> tuple[dict, str | None, list[str]]:
    """Settings for a page from its URL: ``(values, scene, errors)``. A bad field is
    refused alone (it keeps the scene's or the default value, with a message); the
    good ones are kept. Never raises."""
    values, errors = parse_query(args)
    scene = scene_of(args)
    base = base_settings(scene)
    for _ in range(len(QUERY_NAMES)):
        try:
            validate(values)
            return values, scene, errors
        except SettingsError as exc:
            bad = {n for n in exc.fields if values.get(n) != base.get(n)}
            if not bad:     # the field named holds its base value: the other one moved
                bad = {m for n in exc.fields for m in _RELATED.get(n, ())
                       if values.get(m) != base.get(m)}
            if not bad:
                break
            errors.append(f"{exc} — using the {'scene' if scene else 'default'} value of "
                          + ", ".join(sorted(bad)))
            values.update({n: base[n] for n in bad})
    errors.append("these settings do not fit together — using the "
                  + ("scene's settings" if scene else "default settings"))
    return dict(base), scene, errors


def initial_settings(args: Mapping[str, object]) -> tuple[dict, list[str]]:
    """Settings for a new session from its URL (see ``from_query``)."""
    values, _, errors = from_query(args)
    return values, errors
