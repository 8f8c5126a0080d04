"""impactlib: exact simulation of the harmonically forced impact oscillator.

    m x'' + 2 c x' + k x = cos(omega t)   for x > g;   x'(t+) = -r x'(t-) at x = g

Folders: kernels/ (every jitted step of a run and the one event loop), analysis/ (one
parameter set: orbits, Lyapunov exponents, classification, continuation, basins),
sweeps/ (many parameter values), verify/ (independent references and the accuracy
report); simulate.py, model.py and parallel.py at the top.
"""
from . import _aliases
from .analysis.basins import Attractor, BasinRows, Basins, basins, iter_basins
from .analysis.classify import Motion, classify
from .analysis.continuation import Branch, Event, continuation
from .analysis.lyapunov import Lyapunov, lyapunov
from .analysis.orbits import PeriodicOrbit, periodic_orbit
from .model import (FIELDS, METHODS, PARAM_NAMES, MotionCode, Params, RunLimits, RunStatus,
                    rk4_stability_limit)
from .simulate import Impacts, Samples, Solution, simulate
from .sweeps.diagrams import Bifurcation, RegimeMap, bifurcation, iter_bifurcation, regime_map
from .warmup import warmup

_aliases.install(__name__)

__all__ = ["FIELDS", "METHODS", "PARAM_NAMES", "Params", "RunLimits", "rk4_stability_limit",
           "RunStatus", "MotionCode",
           "Impacts", "Samples", "Solution", "simulate", "Motion", "classify",
           "Bifurcation", "RegimeMap", "bifurcation", "iter_bifurcation", "regime_map", "warmup",
           "PeriodicOrbit", "periodic_orbit", "Lyapunov", "lyapunov",
           "Branch", "Event", "continuation",
           "Attractor", "BasinRows", "Basins", "basins", "iter_basins"]
