"""One module per view; each owns its Bokeh figure and ColumnDataSource, built once and
updated in place with a single ``source.data = {...}`` assignment.

Adding a view: write ``app/views/<name>.py`` with a ``View`` subclass (see base.py) and
list it in ``VIEWS`` below; the session builds it, lays it out and feeds it.
"""
from .animation import AnimationView
from .base import View
from .bifurcation import BifurcationView
from .branches import BranchesView
from .displacement import DisplacementView
from .impact_map import ImpactMapView
from .lyapunov import LyapunovView
from .phase import PhaseView
from .poincare import PoincareView

#: The views of a page, in page order.
VIEWS: tuple[type[View], ...] = (DisplacementView, PhaseView, AnimationView, ImpactMapView,
                                 PoincareView, BifurcationView, LyapunovView, BranchesView)

__all__ = ["VIEWS", "AnimationView", "BifurcationView", "BranchesView", "DisplacementView",
           "ImpactMapView", "LyapunovView", "PhaseView", "PoincareView", "View"]
