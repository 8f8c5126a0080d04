"""The core's layout: imports point one way (kernels <- simulate <- analysis <- sweeps;
verify beside them), no cycle, no import deferred into a function except of the
optional accuracy report, and the flat module paths still import the same modules."""
import ast
import importlib
from pathlib import Path

import pytest

import impactlib

ROOT = Path(impactlib.__file__).parent

#: what each part may import from the package (besides itself)
ALLOWED = {
    "_version": set(),
    "io": {"_version"},
    "progress": set(),
    "kernels": {"model"},
    "model": set(),
    "simulate": {"kernels", "model", "io"},
    "parallel": set(),
    "analysis": {"kernels", "model", "simulate", "parallel", "progress", "io"},
    "sweeps": {"kernels", "model", "simulate", "parallel", "progress", "analysis", "io"},
    "verify": {"model", "simulate"},
}
#: deferred imports allowed: the accuracy report needs the optional extra "report"
DEFERRED_OK = {"impactlib.verify.report"}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path):
    """(target module, deferred) for every import of a package module in ``path``."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = ast.parse(path.read_text())
    top = set(map(id, tree.body))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = package.split(".")
            base = base[:len(base) - node.level + 1]
            mod = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                sub = f"{mod}.{alias.name}"
                target = sub if (ROOT.parent / (sub.replace(".", "/") + ".py")).exists() or \
                    (ROOT.parent / sub.replace(".", "/")).is_dir() else mod
                out.append((target, id(node) not in top))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("impactlib"):
                    out.append((alias.name, id(node) not in top))
    return name, out


def part(mod: str) -> str:
    return mod.split(".")[1] if mod.count(".") else "__init__"


GRAPH = dict(imports_of(p) for p in ROOT.rglob("*.py") if p.name != "__main__.py")


def test_imports_point_one_way_and_none_is_deferred():
    for mod, targets in GRAPH.items():
        src = part(mod)
        if src not in ALLOWED:
            continue            # __init__, cli, warmup, _aliases: the package's entry points
        for target, deferred in targets:
            dst = part(target)
            assert dst == src or dst in ALLOWED[src], f"{mod} imports {target}"
            assert not deferred or target in DEFERRED_OK, f"{mod} defers importing {target}"


def test_no_import_cycle():
    graph = {m: {t for t, d in ts if not d and t in GRAPH and t != m} for m, ts in GRAPH.items()}
    # a package imports its submodules through __init__; that edge is no cycle
    state = {}

    def visit(m, stack):
        state[m] = 1
        for t in graph[m]:
            if m.startswith(t + ".") or t == "impactlib":
                continue
            if state.get(t) == 1:
                pytest.fail("import cycle: " + " -> ".join(stack + [m, t]))
            if t not in state:
                visit(t, stack + [m])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [])


@pytest.mark.parametrize("old, new", [
    ("flight", "kernels.flight"), ("events", "kernels.events"), ("tangent", "kernels.tangent"),
    ("classify", "analysis.classify"), ("orbits", "analysis.orbits"),
    ("lyapunov", "analysis.lyapunov"), ("continuation", "analysis.continuation"),
    ("basins", "analysis.basins"), ("distributed", "sweeps.distributed"),
    ("compare", "verify.compare"), ("reference", "verify.reference"),
    ("report", "verify.report")])
def test_flat_module_paths_are_the_moved_modules(old, new):
    public = {n: getattr(impactlib, n) for n in impactlib.__all__}
    assert importlib.import_module(f"impactlib.{old}") is importlib.import_module(f"impactlib.{new}")
    # importing a flat path replaces no public name (impactlib.classify stays the function)
    assert all(getattr(impactlib, n) is obj for n, obj in public.items())


def test_public_names_kept():
    assert set(impactlib.__all__) >= {
        "FIELDS", "METHODS", "PARAM_NAMES", "Params", "RunLimits", "rk4_stability_limit",
        "Impacts", "Samples", "Solution", "simulate", "Motion", "classify", "Bifurcation",
        "RegimeMap", "bifurcation", "iter_bifurcation", "regime_map", "warmup",
        "PeriodicOrbit", "periodic_orbit", "Lyapunov", "lyapunov", "Branch", "Event",
        "continuation", "Attractor", "BasinRows", "Basins", "basins", "iter_basins"}
    for name in impactlib.__all__:
        assert hasattr(impactlib, name)
