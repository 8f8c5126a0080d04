"""The stability readout of a scene: the periodic orbit the motion settles on, with its
Floquet multipliers, or the two Lyapunov exponents of a motion that does not settle.

The motion is the scene's own (its start, window and physics) run by the exact method:
stability is a property of the oscillator, not of the integrator the scene compares. A
motion has settled on a period-n orbit when its Poincaré points (section t = 0 mod T)
repeat after n periods at the end of the window; the orbit is then polished by
``il.periodic_orbit`` from the last point (Newton with the exact Jacobian), and is only
reported if Newton stays on that point. Otherwise both Lyapunov exponents are measured
with an error estimate, continuing from the end of the window over as long again; "chaotic"
is said only when the largest one is positive by more than twice its error (the label
is ``il.classify``'s, the exponents are the same measurement).

Readouts are shared by all sessions (``pn.cache`` keyed by the frozen inputs, LRU).
"""
from __future__ import annotations

import cmath
import html
import math
from dataclasses import dataclass

import numpy as np
import panel as pn

import impactlib as il
from impactlib.analysis.classify import measure_lyapunov

from . import compute
from .state import Run

#: Poincaré points closer than this (relative to the orbit's size, at least 1) count as
#: repeating; a period-n orbit is looked for up to MAX_PERIOD periods.
REPEAT_RTOL = 1e-6
MAX_PERIOD = 16
#: Newton may move the point this far (relative) and still be the orbit the motion is on;
#: further for a motion that il.classify calls periodic but is still settling.
SAME_ORBIT_RTOL = 1e-4
SETTLING_RTOL = 1e-2
#: Short words for il.classify's kinds (its full label is on the motion badge).
VERDICTS = {"chaotic": "chaotic: λ₁ is positive by more than twice its error",
            "undetermined": "undetermined: λ₁ is not beyond twice its error from 0 — "
                            "lengthen the window"}


@dataclass(frozen=True)
class Readout:
    """What the readout says about one motion.

    kind : "orbit" (settled on a periodic orbit), "exponents" (not periodic in the
        window: Lyapunov exponents) or "failed".
    verdict : one line in words ("stable", "chaotic", "sticks to the wall", ...).
    orbit : il.PeriodicOrbit or None.  lyapunov : il.Lyapunov or None.
    """

    kind: str
    verdict: str
    orbit: object = None
    lyapunov: object = None

    @property
    def sticks(self) -> bool:
        return bool((self.orbit is not None and self.orbit.sticks)
                    or (self.lyapunov is not None and self.lyapunov.sticks))


def readout_key(run: Run) -> tuple:
    """What the readout depends on: the physics, the scene's start and window
    (``Run.scene_start``; not the scene's integration method, not the section, not the
    diagram)."""
    x0, v0, t_record = run.scene_start
    return (run.params, x0, v0, run.t_end, t_record)


def repeat_period(px: np.ndarray, pv: np.ndarray, max_period: int = MAX_PERIOD) -> int:
    """Smallest n such that the last two Poincaré points repeat after n periods
    (0: none up to ``max_period``)."""
    if px.size < 3:
        return 0
    tol = REPEAT_RTOL * max(1.0, float(np.max(np.abs(px[-8:]))), float(np.max(np.abs(pv[-8:]))))
    for n in range(1, max_period + 1):
        if px.size < n + 2:
            break
        if all(abs(px[-1 - j] - px[-1 - j - n]) <= tol and abs(pv[-1 - j] - pv[-1 - j - n]) <= tol
               for j in (0, 1)):
            return n
    return 0


def orbit_at(p: il.Params, n: int, x: float, v: float, rtol: float, phase: float = 0.0):
    """The period-n orbit through (x, v) on the section t = phase, or None: Newton from there
    must converge and stay within ``rtol`` (relative) of it. A stable orbit of a period
    dividing n is preferred (a period-1 orbit settled onto slowly, through multipliers
    near -1, also nearly repeats after 2); an unstable one is not what the motion is on
    (just past a period doubling, the period-2 motion passes near the period-1 orbit)."""
    scale = max(1.0, abs(x), abs(v))
    for d in [d for d in range(1, n) if n % d == 0] + [n]:
        orb = il.periodic_orbit(p, d, x0=x, v0=v, phase=phase)
        near = orb.converged and max(abs(orb.x - x), abs(orb.v - v)) <= rtol * scale
        if near and (d == n or orb.stable):
            return orb
    return None


def exact_run(key: tuple, source) -> il.Solution:
    """The exact run of ``readout_key`` ``key``: the scene's own run when the scene is
    computed by the exact method (``source`` = its (scene key, section phase)), else a
    run of its own with the section at t = 0."""
    if source is not None:
        return compute.simulate(source[0], True, source[1])
    p, x0, v0, t_end, t_record = key
    return il.simulate(p, t_end=t_end, t_record=t_record, x0=x0, v0=v0, phase=0.0,
                       limits=compute.scene_limits("exact"))


def settled_orbit(sol: il.Solution):
    """The periodic orbit the exact run ``sol`` has settled on by its end, or None: an
    ``il.PeriodicOrbit`` on the run's section, converged, on its last section point."""
    px, pv = np.asarray(sol.poincare.x), np.asarray(sol.poincare.v)
    n = repeat_period(px, pv) if sol.status == il.RunStatus.OK else 0
    if n == 0:
        return None
    return orbit_at(sol.params, n, float(px[-1]), float(pv[-1]), SAME_ORBIT_RTOL, sol.phase)


def _stability_readout(key: tuple, source) -> Readout:
    sol = exact_run(key, source)
    orb = settled_orbit(sol)
    settling = ""
    ly = None
    if orb is None:
        # il.classify's looser test may see a period the strict one missed (an orbit
        # still settling, with a multiplier near the unit circle, or a period above 16)
        motion, ly = compute.classified(sol)
        if motion.kind == "periodic" and math.isfinite(motion.period) and len(sol.poincare):
            orb = orbit_at(sol.params, int(motion.period), float(sol.poincare.x[-1]),
                           float(sol.poincare.v[-1]), SETTLING_RTOL, sol.phase)
            orb = orb if orb is not None and orb.stable else None
            settling = " (the motion is still settling onto it at the end of the window)"
    if orb is not None:
        if orb.sticks:
            verdict = ("sticks to the wall in every cycle: the release time is fixed by the "
                       "forcing alone, so the map is locally constant — multipliers 0 "
                       "(superstable)")
        else:
            verdict = "stable" if orb.stable else "unstable (the motion is leaving it)"
        return Readout("orbit", verdict + settling, orbit=orb)
    # The label is il.classify's, which measures before it says "chaotic"; the exponents
    # shown are that measurement (made here, by the same rule, where the maps decided
    # without one).
    if ly is None:
        ly = measure_lyapunov(sol)
    return Readout("exponents", motion_verdict(motion, ly), lyapunov=ly)


def motion_verdict(motion, ly) -> str:
    """One line for a motion that is not periodic: ``il.classify``'s word (the short
    form of "chaotic", and of "undetermined" when that is about λ₁ within its error),
    then what the exponents shown are when they are not numbers (−∞, NaN)."""
    if motion.kind == "chaotic" or (motion.kind == "undetermined"
                                    and math.isfinite(motion.lyapunov)):
        text = VERDICTS[motion.kind]
    else:
        text = motion.label
    if ly.sticks:
        if "sticks" not in text:
            text += " — the motion sticks to the wall: its Jacobian vanishes, exponents −∞"
    elif ly.unbounded:
        if "unbounded" not in text:
            text += " — the impact speed keeps growing: no exponents (NaN)"
    elif not math.isfinite(float(ly.exponents[0])):
        text += f" — no exponents: {ly.message}"
    return text


@dataclass(frozen=True)
class Source:
    """Where the readout's exact run comes from (see :func:`exact_run`): not part of the
    readout's cache key, since every source gives the same motion."""

    scene: tuple | None


@pn.cache(max_items=64, policy="LRU",
          hash_funcs={il.Params: lambda p: repr(p).encode(), Source: lambda s: b"source"})
def stability_readout(key: tuple, source: Source = Source(None)) -> Readout:
    """The readout of ``readout_key(run)``, cached across sessions, computed from the
    run ``source`` names on a miss."""
    return _stability_readout(key, source.scene)


def scene_source(run: Run) -> Source:
    """``run``'s scene (its key and section phase) when it is the exact run the readout
    needs."""
    if run.method != "exact":
        return Source(None)
    return Source((run.scene_key(), compute.section_phase(run)))


def readout(run: Run) -> Readout:
    """The stability readout of ``run``'s motion (a ``failed`` one instead of raising)."""
    try:
        return stability_readout(readout_key(run), scene_source(run))
    except ValueError as exc:
        return Readout("failed", f"no readout: {exc}")


def _number(z: complex) -> str:
    if abs(z.imag) < 1e-12 * max(1.0, abs(z)):
        return f"{z.real:.4f}".replace("-", "−")
    sign = "+" if z.imag >= 0 else "−"
    return f"{z.real:.4f} {sign} {abs(z.imag):.4f}i".replace("-", "−")


def _exponent(x: float) -> str:
    if x == -math.inf:
        return "−∞"
    return "NaN" if x != x else f"{x:+.4f}".replace("-", "−")


def to_html(r: Readout) -> str:
    """The readout as one or two lines of HTML."""
    if r.kind == "failed":
        return f"Stability: {html.escape(r.verdict)}"
    if r.kind == "orbit":
        o = r.orbit
        label = o.label + (" with sticking" if o.sticks and "sticking" not in o.label else "")
        mus = ", ".join(f"μ{i + 1} = {_number(complex(m))}" for i, m in enumerate(o.multipliers))
        mods = ", ".join(f"{abs(m):.4f}" for m in o.multipliers)
        arg = ""
        if not o.sticks and abs(complex(o.multipliers[0]).imag) > 0:
            arg = f", arg μ1 = {cmath.phase(complex(o.multipliers[0])):.3f} rad"
        return (f"Stability: settled on the <b>{html.escape(label)}</b> orbit · Floquet "
                f"multipliers {mus} (|μ| = {mods}{arg}) · <b>{html.escape(r.verdict)}</b>")
    ly = r.lyapunov
    lam = ", ".join(f"λ{i + 1} = {_exponent(e)} ± {er:.2g}" if math.isfinite(e) else
                    f"λ{i + 1} = {_exponent(e)}" for i, (e, er) in
                    enumerate(zip(ly.exponents, ly.error)))
    return (f"Stability: not periodic in the window · Lyapunov exponents {lam} per unit "
            f"time, measured over [{ly.window[0]:g}, {ly.window[1]:g}] s ({ly.n_impacts} "
            f"impacts) · "
            f"<b>{html.escape(r.verdict)}</b>")
