"""The impact oscillator's parameters (Lee, "Motion behavior of impact oscillator", Eq. 1).

    m x'' + 2 c x' + k x = cos(omega t)      while x > g
    x = g, x' < 0:  x'(t+) = -r x'(t-)

Validation lives here and in :func:`check_run`, and runs once, in Python, before any kernel.
"""
from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass

import numpy as np

PARAM_NAMES = ("m", "c", "k", "g", "r", "omega")
METHODS = ("exact", "rk4", "rk45")


class RunStatus(enum.IntEnum):
    """How a run ended (Solution.status and every kernel's status code)."""

    OK = 0              # reached t_end
    IMPACT_LIMIT = 1    # stopped at max_impacts
    STEP_LIMIT = 2      # stopped at max_steps
    OUTPUT_FULL = 3     # more impacts in the window than the output holds


class MotionCode(enum.IntEnum):
    """Codes in the (m, n) arrays of a classification (classify's kernel, RegimeMap)
    where a count of impacts or periods does not apply; counts are >= 0."""

    INFINITE = -1       # m: complete chattering (a chatter summed); n: no period found
    UNDETERMINED = -2   # the record window is shorter than 4 periods
    NOT_SETTLED = -3    # m: a transient still approaching a period-n orbit
    UNBOUNDED = -4      # m: the impact speed grows every cycle (no dissipation)


RUN_MESSAGES = {
    RunStatus.OK: "reached t_end",
    RunStatus.IMPACT_LIMIT: "stopped at the impact limit (max_impacts); results up to that time",
    RunStatus.STEP_LIMIT: "stopped at the step limit (max_steps); results up to that time",
    RunStatus.OUTPUT_FULL: "more impacts in the record window than the output holds; the rest "
                           "were not kept",
}
#: Magnitudes the closed form can represent: beyond them its constants (c/m, k/m, m*m,
#: (2 c omega)^2, the period 2 pi/omega) overflow or underflow double precision.
MAGNITUDE_MAX = 1e50
MAGNITUDE_MIN = 1e-50      # smallest m and omega


@dataclass(frozen=True)
class Field:
    """A parameter's name, meaning and valid range (``lo``/``hi``: None for unbounded;
    ``lo_open``: the lower bound itself is excluded)."""

    symbol: str
    label: str
    unit: str
    doc: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False


FIELDS = {
    "m": Field("m", "mass", "", "mass of the oscillator (> 0)", lo=0.0, lo_open=True),
    "c": Field("c", "damping", "", "damping coefficient; the equation carries 2c, so c = sqrt(k m) is critical (>= 0)", lo=0.0),
    "k": Field("k", "stiffness", "", "spring stiffness (>= 0)", lo=0.0),
    "g": Field("g", "endstop", "", "position of the rigid endstop; g > 0 preloads the spring, g < 0 is a gap"),
    "r": Field("r", "restitution", "", "coefficient of restitution, 0 (plastic) to 1 (elastic)", lo=0.0, hi=1.0),
    "omega": Field("ω", "driving frequency", "rad/s", "angular frequency of the unit harmonic force (> 0)",
                   lo=0.0, lo_open=True),
}


def _as_float(name, value, problems):
    if isinstance(value, bool) or value is None:
        problems.append(f"{name}={value!r} is not a number")
        return math.nan
    try:
        out = float(value)
    except (TypeError, ValueError):
        problems.append(f"{name}={value!r} is not a number")
        return math.nan
    if not math.isfinite(out):
        problems.append(f"{name}={out!r} is not finite")
    return out


def _param_problems(values: dict) -> list[str]:
    problems: list[str] = []
    f = {n: _as_float(n, values[n], problems) for n in PARAM_NAMES}
    for n in PARAM_NAMES:
        x, lo, hi = f[n], FIELDS[n].lo, FIELDS[n].hi
        if hi is not None:
            if not (lo <= x <= hi) and math.isfinite(x):
                problems.append(f"{n}={x!r} must lie in [{lo:g}, {hi:g}]")
        elif lo is not None and FIELDS[n].lo_open and x <= lo:
            problems.append(f"{n}={x!r} must be > {lo:g}")
        elif lo is not None and x < lo:
            problems.append(f"{n}={x!r} must be >= {lo:g}")
    for n in PARAM_NAMES:
        if math.isfinite(f[n]) and abs(f[n]) > MAGNITUDE_MAX:
            problems.append(f"{n}={f[n]!r} is beyond {MAGNITUDE_MAX:g} in magnitude "
                            "(the closed form's constants would overflow)")
    for n in ("m", "omega"):
        if 0 < f[n] < MAGNITUDE_MIN:
            problems.append(f"{n}={f[n]!r} must be >= {MAGNITUDE_MIN:g} "
                            "(the closed form's constants would overflow)")
    return problems


@dataclass(frozen=True)
class Params:
    """Physical parameters; frozen, hashable, validated on construction.

    Defaults are the paper's: m = 1, c = 0.05, k = 1, g = 0, r = 0.8, omega = 2.
    """

    m: float = 1.0
    c: float = 0.05
    k: float = 1.0
    g: float = 0.0
    r: float = 0.8
    omega: float = 2.0

    def __post_init__(self):
        values = {n: getattr(self, n) for n in PARAM_NAMES}
        problems = _param_problems(values)
        if problems:
            raise ValueError("invalid parameters: " + "; ".join(problems))
        for n in PARAM_NAMES:
            object.__setattr__(self, n, float(values[n]))

    @property
    def T(self) -> float:
        """Forcing period 2 pi / omega."""
        return 2.0 * math.pi / self.omega

    @property
    def omega_n(self) -> float:
        """Natural frequency sqrt(k / m) of the free, undamped oscillator."""
        return math.sqrt(self.k / self.m)

    def replace(self, **changes) -> "Params":
        unknown = sorted(set(changes) - set(PARAM_NAMES))
        if unknown:
            raise ValueError(f"unknown parameter name(s): {', '.join(map(repr, unknown))}; "
                             f"expected one of {', '.join(PARAM_NAMES)}")
        return dataclasses.replace(self, **changes)

    def as_array(self) -> np.ndarray:
        return np.array([getattr(self, n) for n in PARAM_NAMES], dtype=np.float64)

    def rate(self) -> float:
        """Fastest rate of the linear flow plus forcing, 1/s (sets step and tolerance scales)."""
        return float(fastest_rate(self.m, self.c, self.k, self.omega))


def flow_rate(m, c, k):
    """Largest |eigenvalue| of the unforced linear flow (arrays or scalars), 1/s."""
    m, c, k = (np.asarray(v, dtype=np.float64) for v in (m, c, k))
    a = c / m
    w0sq = k / m
    return np.where(a * a > w0sq, a + np.sqrt(np.abs(a * a - w0sq)), np.sqrt(w0sq))


def fastest_rate(m, c, k, omega):
    """Fastest rate of the linear flow and the forcing (arrays or scalars), 1/s."""
    return np.maximum(np.maximum(flow_rate(m, c, k), omega), np.asarray(c) / m)


@dataclass(frozen=True)
class RunLimits:
    """Work ceilings of one simulation; hitting one stops the run with partial results."""

    max_impacts: int = 1_000_000
    max_steps: int = 20_000_000
    max_samples: int = 5_000_000     # Poincare + dense samples held in memory


#: RK4 is stable for |h lambda| <= 2.785 on the negative real axis and 2.828 on the
#: imaginary axis; the smaller bound, rounded down, is used for every direction.
RK4_STABLE_H_LAMBDA = 2.78


def rk4_stability_limits(m, c, k):
    """Largest stable RK4 step for the linear flow (arrays or scalars), inf if it has no rate."""
    lam = flow_rate(m, c, k)
    with np.errstate(divide="ignore"):
        return np.where(lam == 0, np.inf, RK4_STABLE_H_LAMBDA / lam)


def rk4_stability_limit(p: Params) -> float:
    """Largest stable RK4 step for the linear flow of ``p`` (see :func:`rk4_stability_limits`)."""
    return float(rk4_stability_limits(p.m, p.c, p.k))


def _dense_count(dense, problems: list) -> int:
    """How many dense samples ``dense`` asks for: a whole number >= 0 (evenly spaced), or
    a 1-D array of finite, ascending sample times (its window is checked by the caller)."""
    if isinstance(dense, (int, np.integer)) and not isinstance(dense, bool):
        if dense >= 0:
            return int(dense)
    elif isinstance(dense, (np.ndarray, list, tuple)):
        times = np.asarray(dense)
        if (times.ndim == 1 and times.dtype.kind in "if" and np.all(np.isfinite(times))
                and np.all(np.diff(times) >= 0)):
            return times.size
    problems.append(f"dense={_short_repr(dense)} must be a whole number >= 0 or a 1-D array "
                    "of finite sample times in ascending order")
    return 0


def _short_repr(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_plain_run(p, t_end, t_record, x0, v0, phase, dense, limits):
    """check_run's answer for an exact run given as Python floats (x0 and t_record may be
    None) and a whole number of dense samples, in a few comparisons; None when anything
    is of another type or out of range, so that the full checks word the message."""
    if (type(p) is not Params or type(t_end) is not float or type(v0) is not float
            or type(phase) is not float or type(dense) is not int):
        return None
    if t_record is None:
        t_record = 0.5 * t_end
    elif type(t_record) is not float:
        return None
    if x0 is None:
        x0 = max(0.0, p.g)
    elif type(x0) is not float:
        return None
    period = p.T
    # chained comparisons are false for nan, so a nan anywhere takes the full checks
    if (0.0 < t_end < math.inf and 0.0 <= t_record <= t_end and p.g <= x0 < math.inf
            and -math.inf < v0 < math.inf and 0.0 <= phase <= period and dense >= 0
            and (t_end - t_record) / period + 2 + dense <= limits.max_samples):
        return t_end, t_record, x0, v0, phase
    return None


def check_run(p: Params, *, t_end, t_record, x0, v0, phase, method, dt, rtol, atol,
              dense, limits: RunLimits) -> tuple:
    """Validate a run's settings; return them as floats. One ValueError names every bad field."""
    if method == "exact":
        plain = check_plain_run(p, t_end, t_record, x0, v0, phase, dense, limits)
        if plain is not None:
            return plain + (dt, rtol, atol)
    problems: list[str] = []
    if not isinstance(p, Params):
        raise TypeError(f"p must be impactlib.Params, got {type(p).__name__}")
    if method not in METHODS:
        problems.append(f"method={method!r} is unknown; expected one of {', '.join(METHODS)}")
    t_end = _as_float("t_end", t_end, problems)
    t_record_given = t_record is not None
    # t_record defaults to half the run (the paper's 250 of 500); nan if t_end is bad
    t_record = 0.5 * t_end if t_record is None else _as_float("t_record", t_record, problems)
    x0 = max(0.0, p.g) if x0 is None else _as_float("x0", x0, problems)
    v0 = _as_float("v0", v0, problems)
    phase = _as_float("phase", phase, problems)
    if math.isfinite(t_end) and t_end <= 0:
        problems.append(f"t_end={t_end!r} must be > 0")
    # a t_record derived from a bad t_end is not the user's value: name it only if given
    if math.isfinite(t_record) and math.isfinite(t_end) and t_end > 0:
        if not (0.0 <= t_record <= t_end):
            problems.append(f"t_record={t_record!r} must lie in [0, t_end={t_end!r}]")
    elif t_record_given and math.isfinite(t_record) and t_record < 0:
        problems.append(f"t_record={t_record!r} must be >= 0")
    if math.isfinite(x0) and x0 < p.g:
        problems.append(f"x0={x0!r} is behind the endstop g={p.g!r} (need x0 >= g)")
    if math.isfinite(phase) and not (0.0 <= phase <= p.T):
        problems.append(f"phase={phase!r} must lie in [0, T={p.T!r}] (time units)")
    n_dense = _dense_count(dense, problems)
    if method == "rk4":
        if dt is None:
            problems.append("dt is required for method='rk4'")
        else:
            dt = _as_float("dt", dt, problems)
            if math.isfinite(dt):
                lim = rk4_stability_limit(p)
                if dt <= 0:
                    problems.append(f"dt={dt!r} must be > 0")
                elif dt > lim:
                    problems.append(f"dt={dt!r} exceeds the RK4 stability limit {lim:.4g} for these "
                                    f"parameters (fastest rate {RK4_STABLE_H_LAMBDA / lim:.4g} 1/s)")
    if method == "rk45":
        rtol = _as_float("rtol", rtol, problems)
        atol = _as_float("atol", atol, problems)
        if math.isfinite(rtol) and not (1e-14 <= rtol < 1):
            problems.append(f"rtol={rtol!r} must lie in [1e-14, 1)")
        if math.isfinite(atol) and not (0 < atol < 1):
            problems.append(f"atol={atol!r} must lie in (0, 1)")
    if not problems and not isinstance(dense, (int, np.integer)):
        times = np.asarray(dense)
        if times.size and not (t_record <= times[0] and times[-1] <= t_end):
            problems.append(f"dense: sample times [{float(times[0])!r} ... {float(times[-1])!r}] must lie "
                            f"in the window [t_record, t_end] = [{t_record!r}, {t_end!r}]")
    if not problems:
        n_sec = (t_end - t_record) / p.T + 2
        n_samples = n_sec + n_dense
        if n_samples > limits.max_samples:
            problems.append(
                f"the window [t_record, t_end] = [{t_record!r}, {t_end!r}] holds {n_sec:.3g} forcing "
                f"periods at omega={p.omega!r}; with {n_dense} dense samples that is over the "
                f"limit of {limits.max_samples} samples")
    if problems:
        raise ValueError("invalid run: " + "; ".join(problems))
    return t_end, t_record, x0, v0, phase, dt, rtol, atol
