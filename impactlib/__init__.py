"""impactlib: exact simulation of the harmonically forced impact oscillator.

    m x'' + 2 c x' + k x = cos(omega t)   for x > g;   x'(t+) = -r x'(t-) at x = g
"""
from . import numba_cache  # noqa: F401  (first: sets the cache directory before any kernel)
from ._version import __version__
from .basins import Attractor, BasinRows, Basins, basins, iter_basins
from .boundary import Boundary, BoundaryPoint, boundary
from .classify import Motion, classify
from .continuation import Branch, Event, continuation
from .lyapunov import Lyapunov, lyapunov
from .orbits import PeriodicOrbit, periodic_orbit
from .model import FIELDS, METHODS, PARAM_NAMES, Params, RunLimits, rk4_stability_limit
from .simulate import Impacts, Samples, Solution, simulate
from .sweeps import Bifurcation, RegimeMap, bifurcation, iter_bifurcation, regime_map
from .streaming import iter_regime_map
from .warmup import warmup
from . import io  # impactlib.io.read_csv, write_csv

__all__ = ["__version__", "FIELDS", "METHODS", "PARAM_NAMES", "Params", "RunLimits", "rk4_stability_limit",
           "Impacts", "Samples", "Solution", "simulate", "Motion", "classify",
           "Bifurcation", "RegimeMap", "bifurcation", "iter_bifurcation", "regime_map",
           "iter_regime_map", "warmup",
           "PeriodicOrbit", "periodic_orbit", "Lyapunov", "lyapunov",
           "Branch", "Event", "continuation",
           "Attractor", "BasinRows", "Basins", "basins", "iter_basins",
           "Boundary", "BoundaryPoint", "boundary"]
