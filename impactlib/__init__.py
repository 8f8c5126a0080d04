"""impactlib: exact simulation of the harmonically forced impact oscillator.

    m x'' + 2 c x' + k x = cos(omega t)   for x > g;   x'(t+) = -r x'(t-) at x = g

Folders: kernels/ (every jitted step of a run and the one event loop), analysis/ (one
parameter set: orbits, Lyapunov exponents, classification, continuation, basins),
sweeps/ (many parameter values), verify/ (independent references and the accuracy
report); simulate.py, model.py and parallel.py at the top.
"""
from . import numba_cache  # noqa: F401  (first: sets the cache directory before any kernel)
from . import _aliases
from ._version import __version__
from .analysis.basins import Attractor, BasinRows, Basins, basins, iter_basins
from .analysis.boundary import Boundary, BoundaryPoint, boundary
from .analysis.classify import Motion, classify
from .analysis.continuation import Branch, Event, continuation
from .analysis.lyapunov import Lyapunov, lyapunov
from .analysis.orbits import PeriodicOrbit, periodic_orbit
from .model import (FIELDS, METHODS, PARAM_NAMES, MotionCode, Params, RunLimits, RunStatus,
                    rk4_stability_limit)
from .simulate import Impacts, Samples, Solution, simulate
from .sweeps.diagrams import (Bifurcation, RegimeMap, bifurcation, iter_bifurcation,
                              iter_regime_map, regime_map)
from .warmup import warmup
from . import io  # impactlib.io.read_csv, write_csv

_aliases.install(__name__)

__all__ = ["__version__", "FIELDS", "METHODS", "PARAM_NAMES", "Params", "RunLimits",
           "rk4_stability_limit", "RunStatus", "MotionCode",
           "Impacts", "Samples", "Solution", "simulate", "Motion", "classify",
           "Bifurcation", "RegimeMap", "bifurcation", "iter_bifurcation", "regime_map",
           "iter_regime_map", "warmup",
           "PeriodicOrbit", "periodic_orbit", "Lyapunov", "lyapunov",
           "Branch", "Event", "continuation",
           "Attractor", "BasinRows", "Basins", "basins", "iter_basins",
           "Boundary", "BoundaryPoint", "boundary"]
