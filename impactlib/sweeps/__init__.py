"""Many parameter values at once: bifurcation diagrams and regime maps (diagrams), the
same on a Dask cluster (distributed)."""
from .diagrams import (CAP_PER_VALUE, Bifurcation, RegimeMap, bifurcation, iter_bifurcation,
                       regime_map, worker_count)

__all__ = ["CAP_PER_VALUE", "Bifurcation", "RegimeMap", "bifurcation", "iter_bifurcation",
           "regime_map", "worker_count"]
