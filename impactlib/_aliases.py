"""The flat module paths the package offered before its folders (``impactlib.flight``,
``impactlib.classify``, ``impactlib.report``, ...), for code outside the package that
imports them: each resolves, on first import, to the module object at its place."""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys

#: flat name -> module path inside the package
MOVED = {
    "_jit": "kernels._jit", "flight": "kernels.flight", "events": "kernels.events",
    "integrators": "kernels.integrators", "tangent": "kernels.tangent",
    "engine": "kernels.engine",
    "classify": "analysis.classify", "orbits": "analysis.orbits",
    "lyapunov": "analysis.lyapunov", "continuation": "analysis.continuation",
    "basins": "analysis.basins",
    "distributed": "sweeps.distributed",
    "reference": "verify.reference", "compare": "verify.compare", "report": "verify.report",
    "accuracy": "verify.accuracy",
}


class _Alias(importlib.abc.Loader):
    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        return importlib.import_module(self.target)

    def exec_module(self, module):
        pass


class _MovedFinder(importlib.abc.MetaPathFinder):
    def __init__(self, package: str):
        self.prefix = package + "."
        self.package = package

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith(self.prefix):
            return None
        new = MOVED.get(fullname[len(self.prefix):])
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _Alias(f"{self.package}.{new}"))


def install(package: str) -> None:
    """Register the flat paths of the modules loaded already (an alias loaded later would
    be set as an attribute of the package, over a function of the same name such as
    ``impactlib.classify``), and a finder for the rest."""
    for old, new in MOVED.items():
        mod = sys.modules.get(f"{package}.{new}")
        if mod is not None:
            sys.modules.setdefault(f"{package}.{old}", mod)
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.append(_MovedFinder(package))
