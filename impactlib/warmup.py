"""Compile (or load from the Numba cache) every kernel a served page uses."""
from __future__ import annotations

from .analysis.basins import basins
from .analysis.classify import classify
from .analysis.lyapunov import lyapunov
from .analysis.orbits import periodic_orbit
from .model import Params
from .simulate import simulate
from .sweeps.diagrams import bifurcation, regime_map


def warmup() -> None:
    p = Params()
    sol = simulate(p, t_end=20.0, t_record=10.0, dense=16)
    classify(sol)
    simulate(p, t_end=5.0, t_record=0.0, method="rk4", dt=0.01, dense=4)
    simulate(p, t_end=5.0, t_record=0.0, method="rk45", dense=4)
    bifurcation(p, "omega", [1.0, 2.0], t_end=20.0, t_record=10.0, workers=1)
    bifurcation(p, "omega", [1.0, 2.0], t_end=20.0, t_record=10.0, warm_start="up", workers=1)
    regime_map(p, "omega", [1.0, 2.0], "r", [0.5, 0.8], t_end=20.0, t_record=10.0, workers=1)
    basins(p, (0.0, 0.5), (-0.5, 0.5), n=(2, 2), workers=1)
    periodic_orbit(p)
    lyapunov(p, t_end=40.0, t_record=20.0)
    bifurcation(p, "omega", [1.0, 2.0], t_end=20.0, t_record=10.0, workers=1, lyapunov=True)
