"""CSV downloads of what a session shows: impacts, Poincaré points, bifurcation diagram,
regime map, basins.

The diagram, regime map and basins files start with ``# name = value`` lines: the
settings they were computed with under their URL names (m, c, k, g, r, omega, psi,
t_end, t_record, method), what the view adds (start, sweep mode, grid, legend) and the
``version`` of the package, then one header row, then the rows.
``pandas.read_csv(f, comment="#")`` or ``numpy.loadtxt(f, delimiter=",", comments="#",
skiprows=1)`` read them.
"""
from __future__ import annotations

import io

import numpy as np
import panel as pn
from impactlib.io.header import read_header, settings_lines, write_csv

from .research import attractor_text
from .settings import SWEEP_RANGES, method_options
from .state import to_query, url_number

#: Settings written at the top of every CSV file, by URL name.
HEADER_NAMES = ("m", "c", "k", "g", "r", "omega", "psi", "t_end", "t_record", "method")
#: the app's files keep 10 significant digits (the links' precision)
FMT = "%.10g"
__all__ = ["HEADER_NAMES", "Downloads", "header", "read_header", "to_csv"]


def header(run, extra: dict | None = None) -> str:
    """``# name = value`` lines: the settings of ``run`` (URL names and texts), then
    ``extra`` (replacing a setting of the same name in place, e.g. the method a sweep
    really used), then ``version`` (impactlib's writer)."""
    q = to_query(run)
    values = {n: q.get(n, "") for n in HEADER_NAMES}
    values.update(extra or {})
    return settings_lines(values)


def to_csv(columns: dict, run=None, extra: dict | None = None) -> io.StringIO:
    """A CSV file (the settings of ``run`` and ``extra`` as comment lines, a header
    line, then one row per sample) of equally long columns."""
    buf = io.StringIO()
    if run is not None:
        buf.write(header(run, extra))
    write_csv(buf, {n: np.asarray(c, dtype=float) for n, c in columns.items()}, None, fmt=FMT)
    buf.seek(0)
    return buf


def start_and_section(run) -> dict:
    """Header lines of a scene's file beyond the physics: the start (x0 as used: empty
    means at the wall, max(0, g)), the method's own options, and the section psi in
    both units: time (``psi``, the URL's) and fraction of the period (``psi_over_T``,
    the page's box). A scene started on a periodic orbit is recorded from t = 0 from
    that orbit's state (``Run.scene_start``)."""
    x0, v0, t_record = run.scene_start
    x0 = x0 if x0 is not None else max(0.0, run.params.g)
    out = {"psi": run.psi, "psi_over_T": run.psi_frac, "x0": x0, "v0": v0,
           "t_record": url_number(t_record), "method": run.method}
    out.update(method_options(run, run.method))
    return out


class Downloads:
    """The download buttons of one session; ``session`` has ``run``, ``scene``,
    ``section`` and the ``bifurcation`` view."""

    def __init__(self, session):
        self.session = session
        self._widgets = None

    @property
    def widgets(self) -> list:
        """The buttons, made when first asked for (the drawer's card: a page that never
        opens it never builds them)."""
        if self._widgets is None:
            self._widgets = self._make()
        return self._widgets

    def _make(self) -> list:
        button = dict(color="default", sizing_mode="stretch_width")
        return [
            pn.widgets.FileDownload(callback=self.impacts_csv, filename="impacts.csv",
                                    label="Impacts (CSV)", **button),
            pn.widgets.FileDownload(callback=self.poincare_csv, filename="poincare.csv",
                                    label="Poincaré points (CSV)", **button),
            pn.widgets.FileDownload(callback=self.bifurcation_csv, filename="bifurcation.csv",
                                    label="Bifurcation diagram (CSV)", **button),
        ]

    def _name(self, index: int, what: str) -> None:
        p = self.session.run.params
        self.widgets[index].filename = f"{what}_omega{p.omega:g}_r{p.r:g}_c{p.c:g}_g{p.g:g}.csv"

    def impacts_csv(self) -> io.StringIO:
        self._name(0, "impacts")
        imp = self.session.scene.impacts
        run = self.session.scene.run
        return to_csv({"t": imp["t"], "phase": imp["phase"], "v_before": imp["v"],
                       "v_after": imp["v_after"]}, run, start_and_section(run))

    def poincare_csv(self) -> io.StringIO:
        self._name(1, "poincare")
        s = self.session.section
        run = self.session.run
        return to_csv({"t": s["t"], "x": s["x"], "v": s["v"]}, run, start_and_section(run))

    def bifurcation_csv(self) -> io.StringIO:
        self._name(2, "bifurcation")
        view = self.session.bifurcation
        table = view.table()
        run = view.run
        # the value column is named after the swept parameter; direction only when
        # the sweep has one (+1 up, -1 down)
        cols = {run.bif_param if run is not None else "omega": table["omega"]}
        cols.update((c, table[c]) for c in ("v", "t", "phase"))
        if run is not None and run.bif_sweep != "independent":
            cols["direction"] = table["direction"]
        if run is None:
            return to_csv(cols)
        return to_csv(cols, run, {"method": "exact", "x0": run.x0, "v0": run.v0,
                                  "bif_param": run.bif_param, "bif_sweep": run.bif_sweep,
                                  "bif_min": run.bif_min, "bif_max": run.bif_max,
                                  "bif_n": run.bif_n})

    def regime_map_csv(self, view) -> io.StringIO:
        """One row per computed cell: the two parameters, classify's (m, n) codes and
        the class drawn (its label in the header)."""
        req = view.request
        if req is None:
            return io.StringIO("# nothing computed yet\n")
        run = req.run
        done = ~np.isnan(view.image)
        iy, ix = np.nonzero(done)
        extra = {"method": "exact", "x0": run.x0, "v0": run.v0, "sweep": "independent",
                 "map_x": req.name_x, "map_y": req.name_y, "map_n": req.n}
        for axis, name in (("x", req.name_x), ("y", req.name_y)):
            lo, hi = SWEEP_RANGES[name]
            extra[f"map_{axis}_min"], extra[f"map_{axis}_max"] = lo, hi
        extra["rows_done"] = f"{view.rows_done} of {req.n}"
        for k, label in enumerate(view.labels):
            extra[f"class {k}"] = label
        cols = {req.name_x: req.values_x[ix], req.name_y: req.values_y[iy],
                "m": view.impacts[iy, ix], "n": view.period[iy, ix],
                "class": view.image[iy, ix]}
        return to_csv(cols, run, extra)

    def basins_csv(self, view) -> io.StringIO:
        """One row per computed start: x0, v0 and the attractor it settles on (-1
        undecided; the attractors in the header)."""
        req = view.request
        if req is None:
            return io.StringIO("# nothing computed yet\n")
        run = req.run
        iv, ix = np.nonzero(~np.isnan(view.image))
        extra = {"method": "exact", "sweep": "independent (every start on its own)",
                 "phase": 0.0, "x_min": req.x_range[0], "x_max": req.x_range[1],
                 "v_min": req.v_range[0], "v_max": req.v_range[1], "basins_n": req.n,
                 "rows_done": f"{view.rows_done} of {req.n}"}
        for k, att in enumerate(view.attractors):
            extra[f"attractor {k}"] = attractor_text(att)
        cols = {"x0": view.xs[ix], "v0": view.vs[iv], "attractor": view.image[iv, ix] - 1}
        return to_csv(cols, run, extra)

    def boundaries_csv(self, overlay, request) -> io.StringIO:
        """One row per point of every boundary curve drawn: the two parameters, the
        curve's index, its kind's code and the orbit's state on the section (each curve's
        kind, orbit type, condition and end in the header)."""
        curves = overlay.curves.curves if overlay is not None and overlay.curves else ()
        if request is None or not curves:
            return io.StringIO("# no boundary curves computed yet\n")
        run = request.run
        kinds = ("period-doubling", "saddle-node", "grazing")
        extra = {"method": "exact", "x0": run.x0, "v0": run.v0, "map_x": request.name_x,
                 "map_y": request.name_y, "boundaries": overlay.status,
                 "kinds": "; ".join(f"{k} {name}" for k, name in enumerate(kinds))}
        cols = {request.name_x: [], request.name_y: [], "curve": [], "kind": [], "n": [],
                "impacts": [], "x": [], "v": []}
        for i, b in enumerate(curves):
            extra[f"curve {i}"] = (f"{b.kind} of the {b.orbit} orbit ({b.condition}); "
                                   f"{b.message}")
            k = len(b.values)
            for name, col in ((request.name_x, b.values[:, 0]), (request.name_y, b.values[:, 1]),
                              ("curve", np.full(k, i)), ("kind", np.full(k, kinds.index(b.kind))),
                              ("n", np.full(k, b.n)), ("impacts", np.full(k, b.impacts)),
                              ("x", b.x), ("v", b.v)):
                cols[name].append(col)
        return to_csv({n: np.concatenate(c) for n, c in cols.items()}, run, extra)
