"""impactlib: exact simulation of the harmonically forced impact oscillator.

    m x'' + 2 c x' + k x = cos(omega t)   for x > g;   x'(t+) = -r x'(t-) at x = g
"""
from .model import FIELDS, METHODS, PARAM_NAMES, Params, RunLimits, rk4_stability_limit
from .simulate import Impacts, Samples, Solution, simulate

__all__ = ["FIELDS", "METHODS", "PARAM_NAMES", "Params", "RunLimits", "rk4_stability_limit",
           "Impacts", "Samples", "Solution", "simulate"]
