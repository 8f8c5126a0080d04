"""Shared helpers of the core tests (imported as a plain module: pytest puts this folder on sys.path).

References are expensive (mpmath); they are cached for the whole session by the
``functools.lru_cache`` wrappers in :mod:`impactlib.verify.report` and :func:`mp_cached` below.
"""
from __future__ import annotations

from functools import lru_cache

import impactlib as il
from impactlib.verify.reference import mp_impacts

PAPER = il.Params(m=1.0, c=0.05, k=1.0, g=0.0, r=0.8, omega=2.0)
EPS = 2.220446049250313e-16


@lru_cache(maxsize=None)
def mp_cached(p: il.Params, n: int, x0=None, v0=0.0, t0=0.0, t_max=float("inf")):
    """mp_impacts, cached for the session (arguments must be hashable)."""
    return mp_impacts(p, n, x0=x0, v0=v0, t0=t0, t_max=t_max)
