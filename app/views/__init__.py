"""One module per view; each owns its Bokeh figure and ColumnDataSource, built once and
updated in place with a single ``source.data = {...}`` assignment."""
from .bifurcation import BifurcationView
from .displacement import DisplacementView
from .impact_map import ImpactMapView
from .phase import PhaseView
from .poincare import PoincareView

__all__ = ["BifurcationView", "DisplacementView", "ImpactMapView", "PhaseView",
           "PoincareView"]
