"""How each result is summarised and tabulated (used by :mod:`impactlib.io.result`).

One adapter per result class, found by the class's name: ``summary`` (a title and a few
name/value lines), ``settings`` (the run's parameters and settings by API name),
``frame`` (numeric columns of the tidy table), ``labels`` (its text columns),
``constants`` (columns that are the same on every row: the parameters), ``header_extra``
(text the CSV header carries instead of text columns) and, for sweeps and grids,
``dataset`` (xarray data variables and coordinates).
"""
from __future__ import annotations

import numpy as np

PARAMS = ("m", "c", "k", "g", "r", "omega")


def adapter(result):
    try:
        return ADAPTERS[type(result).__name__]
    except KeyError:
        raise TypeError(f"no table layout for {type(result).__name__}") from None


def _g(x) -> str:
    return "nan" if x is None else f"{x:.6g}"


def _params_text(p, skip=()) -> str:
    return "unknown" if p is None else ", ".join(
        f"{n}={_g(getattr(p, n))}" for n in PARAMS if n not in skip)


def _params(p, skip=()) -> dict:
    return {} if p is None else {n: getattr(p, n) for n in PARAMS if n not in skip}


def _span(values) -> str:
    v = np.asarray(values)
    return "none" if v.size == 0 else f"{v.size} in [{_g(v.min())}, {_g(v.max())}]"


def _counts(labels, top=4) -> str:
    names, counts = np.unique(np.asarray(labels, dtype=object).astype(str), return_counts=True)
    order = np.argsort(-counts, kind="stable")
    parts = [f"{names[i]} ({counts[i]})" for i in order[:top]]
    if order.size > top:
        parts.append(f"{order.size - top} more")
    return "; ".join(parts) if parts else "none"


def _status_text(status) -> str:
    st = np.asarray(status)
    bad = int(np.count_nonzero(st))
    if bad == 0:
        return "ok: every run reached t_end"
    return (f"{bad} of {st.size} runs stopped early (1 impact limit: {int(np.sum(st == 1))}, "
            f"2 step limit: {int(np.sum(st == 2))}, 3 output capped: {int(np.sum(st == 3))})")


def _table(what, table, choices):
    table = choices[0] if table is None else table
    if table not in choices:
        raise ValueError(f"table={table!r} of {what} is unknown; expected one of "
                         f"{', '.join(map(repr, choices))}")
    return table


class _Base:
    @staticmethod
    def labels(r, table):
        return {}

    @staticmethod
    def header_extra(r, table):
        return {}

    @classmethod
    def constants(cls, r):
        return {k: v for k, v in cls.settings(r).items() if isinstance(v, (int, float, str))
                and not isinstance(v, bool)}


class SolutionTables(_Base):
    """Solution tables: ``impacts`` (t, phase, v; v just before impact), ``poincare`` and
    ``dense`` (t, x, v), ``sticking`` (start, release)."""

    TABLES = ("impacts", "poincare", "dense", "sticking")

    @staticmethod
    def summary(s):
        dense = 0 if s.dense is None else len(s.dense)
        return (f"Solution: method={s.method}, status {s.status} ({s.message})", [
            ("params", _params_text(s.params)),
            ("window", f"[{_g(s.t_record)}, {_g(s.t_end)}] s, section phase {_g(s.phase)} s"),
            ("recorded", f"{len(s.impacts)} impacts, {len(s.poincare)} Poincaré points, "
                         f"{len(s.sticking)} sticking intervals, {dense} dense samples"),
            ("run", f"{s.n_impacts} impacts in all, {s.n_chatter} chatter tails summed, "
                    f"{s.nsteps} steps, {s.elapsed * 1e3:.3g} ms"),
            ("final", "t={:.6g}, x={:.6g}, v={:.6g}, stuck={}".format(*s.final)),
        ])

    @staticmethod
    def settings(s):
        out = _params(s.params)
        out.update(method=s.method, t_end=s.t_end, t_record=s.t_record, phase=s.phase)
        out.update(getattr(s, "options", None) or {})
        return out

    @classmethod
    def frame(cls, s, table):
        table = _table("Solution", table, cls.TABLES)
        if table == "impacts":
            return {"t": s.impacts.t, "phase": s.impacts.phase, "v": s.impacts.v}
        if table == "sticking":
            st = np.asarray(s.sticking).reshape(-1, 2)
            return {"start": st[:, 0], "release": st[:, 1]}
        smp = s.poincare if table == "poincare" else s.dense
        if smp is None:
            return {"t": np.empty(0), "x": np.empty(0), "v": np.empty(0)}
        return {"t": smp.t, "x": smp.x, "v": smp.v}

    @staticmethod
    def header_extra(s, table):
        return {"table": table or "impacts"}


class BifurcationTables(_Base):
    """Bifurcation tables: ``impacts`` (one row per recorded impact: the swept value,
    v, t, phase, index, direction) and ``values`` (one row per swept value: status,
    n_impacts, lyapunov)."""

    TABLES = ("impacts", "values")

    @staticmethod
    def summary(b):
        rows = [("params", _params_text(getattr(b, "params", None), (b.name,))),
                ("values", f"{b.name}: {_span(b.values)}"),
                ("impacts", f"{len(b)} recorded"),
                ("status", _status_text(b.status))]
        if b.lyapunov is not None:
            lam = np.asarray(b.lyapunov)
            rows.append(("lyapunov", f"largest exponent per value; {int(np.sum(lam > 0))} "
                                     f"positive, {int(np.sum(np.isneginf(lam)))} stick (-inf), "
                                     f"{int(np.sum(np.isnan(lam)))} NaN"))
        opts = getattr(b, "options", None) or {}
        if opts:
            rows.append(("run", ", ".join(f"{k}={v}" for k, v in opts.items())))
        return f"Bifurcation over {b.name}: {b.values.size} values, {len(b)} impacts", rows

    @staticmethod
    def settings(b):
        out = _params(getattr(b, "params", None), skip=(b.name,))
        out["name"] = b.name
        out.update(getattr(b, "options", None) or {})
        return out

    @classmethod
    def frame(cls, b, table):
        table = _table("Bifurcation", table, cls.TABLES)
        if table == "impacts":
            return {b.name: b.param, "v": b.v, "t": b.t, "phase": b.phase, "index": b.index,
                    "direction": b.direction}
        cols = {b.name: b.values, "status": b.status, "n_impacts": b.n_impacts}
        if b.lyapunov is not None:
            cols["lyapunov"] = b.lyapunov
        return cols

    @staticmethod
    def header_extra(b, table):
        return {"table": table or "impacts"}

    @staticmethod
    def dataset(b):
        dims = {"value": (b.name,), "impact": ("impact",)}
        data = {"v": (dims["impact"], b.v, {"units": "velocity", "long_name": "impact velocity (before)"}),
                "t": (dims["impact"], b.t, {"units": "s"}),
                "phase": (dims["impact"], b.phase, {"units": "s", "long_name": "t mod T"}),
                "value_index": (dims["impact"], b.index.astype(np.int32)),
                "direction": (dims["impact"], b.direction.astype(np.int32)),
                "impact_" + b.name: (dims["impact"], b.param),
                "status": (dims["value"], b.status.astype(np.int32)),
                "n_impacts": (dims["value"], b.n_impacts.astype(np.int32))}
        if b.lyapunov is not None:
            data["lyapunov"] = (dims["value"], np.asarray(b.lyapunov, dtype=float), {"units": "1/s"})
        return data, {b.name: b.values}


def _regime_labels(rm):
    """Each cell's class label, as ``RegimeMap.label`` gives it (one lookup per code)."""
    ny, nx = rm.impacts.shape
    labels = np.empty((ny, nx), dtype=object)
    by_code = {}
    for iy in range(ny):
        for ix in range(nx):
            if (iy, ix) in rm.motions:
                labels[iy, ix] = rm.label(iy, ix)
                continue
            code = (int(rm.impacts[iy, ix]), int(rm.period[iy, ix]))
            if code not in by_code:
                by_code[code] = rm.label(iy, ix)
            labels[iy, ix] = by_code[code]
    return labels


class RegimeMapTables(_Base):
    """RegimeMap table: one row per cell (both parameters, m and n codes, status; the
    class label as text)."""

    @staticmethod
    def summary(rm):
        ny, nx = rm.impacts.shape
        return (f"RegimeMap {rm.name_x} × {rm.name_y}: {ny} × {nx} cells", [
            ("params", _params_text(getattr(rm, "params", None), (rm.name_x, rm.name_y))),
            (rm.name_x, _span(rm.values_x)), (rm.name_y, _span(rm.values_y)),
            ("classes", _counts(_regime_labels(rm))),
            ("status", _status_text(rm.status)),
        ])

    @staticmethod
    def settings(rm):
        out = _params(getattr(rm, "params", None), skip=(rm.name_x, rm.name_y))
        out.update(name_x=rm.name_x, name_y=rm.name_y)
        out.update(getattr(rm, "options", None) or {})
        return out

    @staticmethod
    def frame(rm, table):
        _table("RegimeMap", table, ("cells",))
        ny, nx = rm.impacts.shape
        iy, ix = np.divmod(np.arange(ny * nx), nx)
        return {rm.name_x: rm.values_x[ix], rm.name_y: rm.values_y[iy],
                "m": rm.impacts.ravel(), "n": rm.period.ravel(), "status": rm.status.ravel()}

    @staticmethod
    def labels(rm, table):
        return {"label": _regime_labels(rm).ravel()}

    @staticmethod
    def header_extra(rm, table):
        return {"codes": "m, n: -1 infinite, -2 undetermined; m = -3 not settled, "
                         "-4 unbounded; n = 0 no impact"}

    @staticmethod
    def dataset(rm):
        dims = (rm.name_y, rm.name_x)
        return ({"m": (dims, rm.impacts.astype(np.int32), {"long_name": "impacts per orbit"}),
                 "n": (dims, rm.period.astype(np.int32), {"long_name": "forcing periods per orbit"}),
                 "status": (dims, rm.status.astype(np.int32)),
                 "label": (dims, _regime_labels(rm).astype(str))},
                {rm.name_x: rm.values_x, rm.name_y: rm.values_y})


class BasinsTables(_Base):
    """Basins table: one row per start (x0, v0, attractor index, -1 undecided; forcing
    periods followed); the attractors' labels as text."""

    @staticmethod
    def summary(b):
        nv, nx = b.labels.shape
        atts = "; ".join(f"{a.label} ({100 * f:.3g} %)" for a, f in zip(b.attractors, b.fractions))
        return (f"Basins: {nv} × {nx} starts, {len(b.attractors)} attractors, "
                f"{'complete' if b.complete else 'partial'}", [
                    ("params", _params_text(b.params)),
                    ("starts", f"x0 {_span(b.x)}, v0 {_span(b.v)}, at t = {_g(b.phase)} s"),
                    ("attractors", atts or "none"),
                    ("undecided", f"{100 * b.undecided:.3g} %"),
                    ("message", b.message)])

    @staticmethod
    def settings(b):
        out = _params(b.params)
        out.update(phase=b.phase, x_min=float(b.x[0]), x_max=float(b.x[-1]), nx=int(b.x.size),
                   v_min=float(b.v[0]), v_max=float(b.v[-1]), nv=int(b.v.size))
        return out

    @staticmethod
    def frame(b, table):
        _table("Basins", table, ("starts",))
        nv, nx = b.labels.shape
        iv, ix = np.divmod(np.arange(nv * nx), nx)
        return {"x0": b.x[ix], "v0": b.v[iv], "attractor": b.labels.ravel(),
                "periods": b.periods.ravel()}

    @staticmethod
    def labels(b, table):
        names = np.array([a.label for a in b.attractors] + ["undecided"], dtype=object)
        return {"label": names[b.labels.ravel()]}

    @staticmethod
    def header_extra(b, table):
        out = {f"attractor_{k}": a.label for k, a in enumerate(b.attractors)}
        out["complete"] = b.complete
        return out

    @staticmethod
    def dataset(b):
        dims = ("v0", "x0")
        return ({"attractor": (dims, b.labels.astype(np.int32), {"long_name": "index into the attractors, -1 undecided"}),
                 "periods": (dims, b.periods.astype(np.int32), {"long_name": "forcing periods followed"}),
                 "fraction": (("attractor_index",), np.asarray(b.fractions, dtype=float))},
                {"x0": b.x, "v0": b.v,
                 "attractor_index": np.arange(len(b.attractors), dtype=np.int32),
                 "attractor_label": (("attractor_index",),
                                     np.array([a.label for a in b.attractors], dtype=str))})


def _mults(mu):
    mu = np.asarray(mu)
    return ", ".join(f"{z.real:.4g}{z.imag:+.4g}j (|μ| {abs(z):.4g})" for z in mu.ravel())


class PeriodicOrbitTables(_Base):
    """PeriodicOrbit table: one row per impact of one cycle (time from t = phase, velocity
    before impact)."""

    @staticmethod
    def summary(o):
        return (f"PeriodicOrbit: {o.label}, {'stable' if o.stable else 'unstable'}"
                f"{'' if o.converged else ', NOT converged'}", [
                    ("params", _params_text(o.params)),
                    ("state", f"x={_g(o.x)}, v={_g(o.v)} at t = {_g(o.phase)} (mod T), n={o.n}"),
                    ("multipliers", _mults(o.multipliers)),
                    ("checks", f"admissible={o.admissible}, sticks={o.sticks}, residual "
                               f"{o.residual:.3g}, {o.iterations} Newton steps"),
                    ("message", o.message)])

    @staticmethod
    def settings(o):
        out = _params(o.params)
        out.update(n=o.n, phase=o.phase, x=o.x, v=o.v, label=o.label, stable=o.stable,
                   converged=o.converged)
        for i, z in enumerate(np.asarray(o.multipliers).ravel()):
            out[f"multiplier_{i + 1}"] = complex(z)
        return out

    @staticmethod
    def frame(o, table):
        _table("PeriodicOrbit", table, ("impacts",))
        return {"t": o.impact_times, "v": o.impact_velocities}

    @classmethod
    def constants(cls, o):
        out = _params(o.params)
        out.update(n=o.n, label=o.label, x=o.x, v_section=o.v)
        return out


class BranchTables(_Base):
    """Branch table: one row per point (parameter, x, v on the section, multipliers as
    real and imaginary parts and moduli, stable, admissible, the impacts' times and
    velocities)."""

    @staticmethod
    def summary(b):
        ev = "; ".join(f"{e.kind} at {_g(e.value)}" for e in b.events[:4])
        if len(b.events) > 4:
            ev += f"; {len(b.events) - 4} more"
        p = b.start.params if b.start is not None else None
        return (f"Branch in {b.name}: {b.param.size} points, {b.impacts}-impact period-{b.n}", [
            ("params", _params_text(p, (b.name,))),
            (b.name, _span(b.param)),
            ("stable", f"{int(np.sum(b.stable))} of {b.param.size} points"),
            ("events", ev or "none"),
            ("message", b.message)])

    @staticmethod
    def settings(b):
        out = _params(b.start.params if b.start is not None else None, skip=(b.name,))
        out.update(name=b.name, n=b.n, impacts=b.impacts, phase=b.phase)
        for k, e in enumerate(b.events):
            out[f"event_{k}"] = f"{e.kind} at {b.name} = {e.value!r}"
        return out

    @staticmethod
    def frame(b, table):
        _table("Branch", table, ("points",))
        mu = np.asarray(b.multipliers).reshape(b.param.size, -1)
        cols = {b.name: b.param, "x": b.x, "v": b.v}
        for i in range(mu.shape[1]):
            cols[f"mu{i + 1}_real"] = mu[:, i].real
            cols[f"mu{i + 1}_imag"] = mu[:, i].imag
            cols[f"mu{i + 1}_abs"] = np.abs(mu[:, i])
        cols["stable"] = np.asarray(b.stable, dtype=float)
        cols["admissible"] = np.asarray(b.admissible, dtype=float)
        ti = np.asarray(b.impact_times).reshape(b.param.size, -1)
        vi = np.asarray(b.impact_velocities).reshape(b.param.size, -1)
        for j in range(ti.shape[1]):
            cols[f"impact_t{j}"] = ti[:, j]
            cols[f"impact_v{j}"] = vi[:, j]
        return cols

    @classmethod
    def constants(cls, b):
        return {k: v for k, v in cls.settings(b).items() if not k.startswith("event")}

    @staticmethod
    def dataset(b):
        k = b.param.size
        mu = np.asarray(b.multipliers).reshape(k, -1)
        ti = np.asarray(b.impact_times).reshape(k, -1)
        vi = np.asarray(b.impact_velocities).reshape(k, -1)
        return ({"x": (("point",), b.x), "v": (("point",), b.v),
                 "multiplier_real": (("point", "multiplier"), mu.real.copy()),
                 "multiplier_imag": (("point", "multiplier"), mu.imag.copy()),
                 "stable": (("point",), np.asarray(b.stable, dtype=np.int8)),
                 "admissible": (("point",), np.asarray(b.admissible, dtype=np.int8)),
                 "impact_time": (("point", "impact"), ti),
                 "impact_velocity": (("point", "impact"), vi)},
                {b.name: (("point",), b.param)})


class LyapunovTables(_Base):
    """Lyapunov table: one row per exponent (1, 2): value and standard error, 1/s."""

    @staticmethod
    def summary(ly):
        ex = ", ".join(f"λ{i + 1} = {_g(e)} ± {_g(s)}" for i, (e, s)
                       in enumerate(zip(ly.exponents, ly.error)))
        return (f"Lyapunov: {ex} (1/s)", [
            ("params", _params_text(ly.params)),
            ("window", f"[{_g(ly.window[0])}, {_g(ly.window[1])}] s, {ly.n_impacts} impacts, "
                       f"{_g(ly.nu)} per s"),
            ("status", f"{ly.status}; sticks={ly.sticks}, unbounded={ly.unbounded}"),
            ("message", ly.message)])

    @staticmethod
    def settings(ly):
        out = _params(ly.params)
        out.update(t_record=ly.window[0], t_end=ly.window[1], n_impacts=ly.n_impacts,
                   status=ly.status)
        return out

    @staticmethod
    def frame(ly, table):
        _table("Lyapunov", table, ("exponents",))
        return {"i": np.arange(1, len(ly.exponents) + 1), "exponent": ly.exponents,
                "error": ly.error}


ADAPTERS = {"Solution": SolutionTables, "Bifurcation": BifurcationTables,
            "RegimeMap": RegimeMapTables, "Basins": BasinsTables,
            "PeriodicOrbit": PeriodicOrbitTables, "Branch": BranchTables,
            "Lyapunov": LyapunovTables}

__all__ = ["ADAPTERS", "adapter"]
