"""Research mode's plot area: regime map and basins, built when first opened.

Until research mode is first shown nothing of it exists in the page (no figure, no
Bokeh model), so the page stays light. Opening it builds both tabs' contents and
computes the open tab's picture;
switching to the other tab computes that one if it is not there yet. The buttons
recompute for the current settings; "Cancel" stops the computation (rows so far stay).
One research job per session runs the work (``app.research``) off the event loop and
streams its row blocks back here; a new request supersedes the one under way.
"""
from __future__ import annotations

import dataclasses
import logging
import time

import panel as pn

from . import boundaries, cluster, map_seeds, research

from .controls import NamedHTML
from .jobs import Job
from .page_style import FIGURE_ROW_CSS, FILL_CSS, LEGEND_CSS

log = logging.getLogger(__name__)

MAP, BASINS = "map", "basins"


class ResearchPanel:
    """``current()`` gives the session's latest valid settings and the scene shown
    (``(run, scene)``); ``pick(**settings)`` is what taps on the views do; ``dispatch``
    and ``pool`` are the session's loop and the executor the job runs in;
    ``on_curves(request, curves)`` hears of each complete set of boundary curves."""

    def __init__(self, widgets: dict, *, dispatch, pool, current, pick, downloads,
                 on_curves=lambda request, curves: None):
        self._widgets, self._current, self._pick = widgets, current, pick
        self._on_curves = on_curves
        self._downloads = downloads
        self.job = Job("research", self._work, dispatch, pool=pool)
        self.boundary_job = Job("boundaries", self._boundary_work, dispatch, pool=pool)
        self.overlay = None                 # the boundary curves on the map, once built
        self._boundary_key = None           # key of the curves asked for (None: none)
        self.boundary_request = None        # the request of the curves asked for
        self._boundary_cells = None         # the map's cells they were asked with
        self._cells = None                  # the cells of the map shown (map_seeds.MapCells)
        self._boundary_where = ""           # where the curves are computed
        self.views: dict = {}               # kind -> view, once built
        self.running: str | None = None     # kind being computed
        self._keys: dict = {}               # kind -> key of the request shown
        self._scene = None
        self._t0 = 0.0
        self.where = ""                     # where the running picture is computed
        self.room = pn.Column(sizing_mode="stretch_both", css_classes=["ie-research"],
                              margin=0)

    @property
    def built(self) -> bool:
        return bool(self.views)

    # -- building -------------------------------------------------------------------------

    def open(self):
        """Research mode is shown: build it the first time, compute the open tab's
        picture unless it is there; returns the plot area."""
        if not self.built:
            self.build()
        self._open(self.tabs.active)
        return self.room

    def build(self) -> None:
        """Make both views and the tabs (first opening only)."""
        from .views.basins import BasinsView
        from .views.regime_map import RegimeMapView
        from .views._figure import Kit
        from .views.boundaries import BoundaryOverlay
        kit = Kit()
        self.views = {MAP: RegimeMapView(kit), BASINS: BasinsView(kit)}
        self.overlay = BoundaryOverlay(self.views[MAP], self._pick)
        self.boundary_status = NamedHTML("", model_name="boundaries_status",
                                         css_classes=["ie-boundaries-status"])
        for view in self.views.values():      # on a tablet or phone the room scrolls
            view.figure.min_height = 360
        for view in self.views.values():
            view.connect(self._pick)
        self.status, self.progress, self.legend, self.buttons = {}, {}, {}, {}
        tabs = []
        for kind, label, names in ((MAP, "Compute regime map",
                                    ("map_x", "map_y", "map_n", "boundaries")),
                                   (BASINS, "Compute basins", ("basins_n",))):
            view = self.views[kind]
            button = pn.widgets.Button(label=label, color="primary", width=170,
                                       css_classes=[f"ie-{kind}-compute"])
            button.on_click(lambda event, k=kind: self.compute(k))
            stop = pn.widgets.Button(label="Cancel", width=80, css_classes=[f"ie-{kind}-cancel"])
            stop.on_click(lambda event: self.cancel())
            self.buttons[kind] = button
            if kind == MAP:       # the boundary curves' points (the switch sits in names)
                curves_csv = pn.widgets.FileDownload(
                    callback=lambda: self._downloads.boundaries_csv(
                        self.overlay, self.views[MAP].request),
                    filename="boundaries.csv", label="Curves (CSV)", width=110,
                    margin=(6, 10), css_classes=["ie-boundaries-csv"])
            save = pn.widgets.FileDownload(
                callback=lambda v=view: getattr(self._downloads, f"{v.key}_csv")(v),
                filename=f"{view.key}.csv", label="CSV", width=70,
                css_classes=[f"ie-{kind}-csv"])
            self.progress[kind] = pn.indicators.Progress(value=0, max=100, width=120,
                                                         height=14, margin=(14, 10))
            self.status[kind] = NamedHTML("", model_name=f"{view.key}_status",
                                          css_classes=[f"ie-{kind}-status"],
                                          sizing_mode="stretch_width")
            self.legend[kind] = pn.pane.HTML(view.legend, width=250, stylesheets=[LEGEND_CSS],
                                             css_classes=[f"ie-{kind}-legend"])
            for n in names:             # (in the sidebar they would stretch; here not)
                self._widgets[n].param.update(sizing_mode="fixed", width=120)
            controls = pn.Row(*(self._widgets[n] for n in names), button, stop, save,
                              sizing_mode="stretch_width", stylesheets=[FILL_CSS])
            controls.extend([self.progress[kind], self.status[kind]])
            tabs.append((
                "Regime map" if kind == MAP else "Basins",
                pn.Column(controls,
                          pn.Row(pn.pane.Bokeh(view.figure, sizing_mode="stretch_both"),
                                 pn.Column(self.legend[kind], self.boundary_status,
                                           curves_csv, width=270)
                                 if kind == MAP else self.legend[kind],
                                 sizing_mode="stretch_both",
                                 stylesheets=[FILL_CSS, FIGURE_ROW_CSS]),
                          sizing_mode="stretch_both", stylesheets=[FILL_CSS])))
        self.tabs = pn.Tabs(*tabs, dynamic=True, sizing_mode="stretch_both",
                            stylesheets=[FILL_CSS])
        self.tabs.param.watch(lambda event: self._open(event.new), "active")
        self.room.objects = [self.tabs]
        if self._scene is not None:
            self.show_scene(self._scene)

    def _open(self, index: int) -> None:
        """A tab is shown: compute its picture unless it is there or under way."""
        kind = (MAP, BASINS)[index]
        if kind not in self._keys and self.running != kind:
            self.compute(kind)

    # -- the work ---------------------------------------------------------------------------

    def compute(self, kind: str) -> None:
        """Compute the regime map (``MAP``) or the basins (``BASINS``) of the current
        settings; supersedes the one under way."""
        run, scene = self._current()
        if run is None:
            return
        if not self.built:
            self.build()
        if kind == MAP:
            request = research.map_request(run)
        else:
            shown = scene.trajectory if scene is not None and scene.run.params == run.params \
                else None
            request = research.BasinsRequest(run, *research.basins_window(run, shown),
                                             run.basins_n)
        self.started(kind, request)
        self.job.submit((kind, request))
        if kind == MAP:
            self._draw_boundaries(run if run.boundaries else None)

    def cancel(self) -> None:
        self.job.cancel()
        self.cancelled()

    def _work(self, job, ticket) -> None:
        """Stream the blocks of a regime map or basins picture to this panel."""
        kind, request = job
        block = None
        client, where = cluster.client()     # None: on this server's threads
        ticket.send(self.located, where)
        try:
            blocks = (research.map_rows(request, client=client) if kind == MAP
                      else research.basins_rows(request, client=client))
            try:
                for block in blocks:
                    ticket.send(self.rows, kind, block)
                    if not ticket.live:       # before the next block is computed
                        break
            finally:
                blocks.close()
        except Exception as exc:     # a message on the view, one log line, no traceback
            log.warning("%s failed: %s: %s", kind, type(exc).__name__, exc)
            ticket.send(self.failed, kind, cluster.failure_text(exc, client))
        else:
            ticket.send(self.finished, kind, block)
        ticket.finish()

    # -- what the session shows -------------------------------------------------------------

    def started(self, kind: str, request) -> None:
        if self.running is not None and self.running != kind:
            self.cancelled()
        self.running = kind
        self._t0 = time.perf_counter()
        self._keys[kind] = request.key()
        if kind == MAP:
            if self._cells is not None:
                self._cells.give_up()
            self._cells = map_seeds.MapCells(request.key())
        self.views[kind].started(request)
        self.legend[kind].object = self.views[kind].legend
        self.progress[kind].value = 0
        self.status[kind].object = "computing…"
        self.buttons[kind].disabled = True

    def located(self, where: str) -> None:
        """Where the picture under way is computed ("" without a cluster setting)."""
        self.where = where

    def _at(self) -> str:
        return f" — {self.where}" if self.where else ""

    def rows(self, kind: str, block) -> None:
        view = self.views[kind]
        view.rows(block)
        self.legend[kind].object = view.legend
        self.progress[kind].value = int(100 * block.rows_done / block.rows_total)
        self.status[kind].object = (f"computing… {block.rows_done}/{block.rows_total} rows"
                                    f"{self._at()}")

    def finished(self, kind: str, block) -> None:
        """The last block arrived (``block`` None: there was none)."""
        self.running = None
        self.buttons[kind].disabled = False
        message = block.message if block is not None else "nothing computed"
        complete = block is not None and block.rows_done == block.rows_total
        elapsed = time.perf_counter() - self._t0
        head = (f"complete: {block.rows_total} rows in {elapsed:.2f} s" if complete
                else f"partial: {block.rows_done if block else 0} rows in {elapsed:.2f} s")
        text = head if message == "complete" else f"{head} — {message}"
        self.status[kind].object = text + self._at()
        self.views[kind].finished("complete" if complete else "partial")
        if kind == MAP and self._cells is not None:
            view = self.views[MAP]
            self._cells.fill(view.request.values_x, view.request.values_y, view.impacts,
                             view.period, complete)
            self._cells_ready()

    def failed(self, kind: str, text: str) -> None:
        self.running = None
        self._keys.pop(kind, None)
        self.buttons[kind].disabled = False
        self.status[kind].object = f"not computed — {text}{self._at()}"
        self.views[kind].finished("not computed")
        if kind == MAP and self._cells is not None:
            self._cells.give_up()

    def cancelled(self) -> None:
        """The running computation was stopped (cancel button or superseded)."""
        kind, self.running = self.running, None
        if kind is None:
            return
        view = self.views[kind]
        if kind == MAP and self._cells is not None:
            self._cells.give_up()
        self.buttons[kind].disabled = False
        self.status[kind].object = (f"cancelled after {view.rows_done} rows — press "
                                    f"{self.buttons[kind].name!r} to compute again")
        view.finished("cancelled")

    def show_scene(self, scene) -> None:
        self._scene = scene
        for view in self.views.values():
            view.show_scene(scene)

    def show_settings(self, run) -> None:
        """Say on a picture when the settings it depends on changed since it was made
        (moving the marked point or the start does not count); the boundary curves go
        with the map shown while its settings hold and the switch is on."""
        if self.overlay is not None and self.views[MAP].request is not None:
            fresh = research.map_request(run).key() == self._keys.get(MAP)
            self._draw_boundaries(self.views[MAP].request.run
                                  if run.boundaries and fresh else None)
        for kind, view in self.views.items():
            req = view.request
            if req is None or self.running == kind:
                continue
            if kind == MAP:
                now = research.map_request(run).key()
            else:
                now = dataclasses.replace(req, run=run).key()
            view.mark_stale(now != self._keys.get(kind))

    # -- boundary curves over the map --------------------------------------------------------

    def _draw_boundaries(self, run, again: bool = False) -> None:
        """Boundary curves of the map computed with ``run``, seeded also from that map's
        cells once it is done (None: none; a change of request, or a new computation of
        the map, cancels the one under way)."""
        req = None if run is None else boundaries.BoundaryRequest(run, run.map_x, run.map_y,
                                                                  self._cells)
        key = None if req is None else req.key()
        if (key == self._boundary_key and not again
                and (req is None or req.cells is self._boundary_cells)):
            return
        self._boundary_key = key
        self._boundary_cells = None if req is None else req.cells
        self.boundary_request = req
        self.boundary_job.cancel()
        self.overlay.clear("" if req is None else "computing…")
        self.boundary_status.object = "" if req is None else self.overlay.legend()
        if req is not None:
            self.boundary_job.submit(req)

    def _boundary_work(self, req, ticket) -> None:
        """Stream the boundary curves to the overlay, off the event loop (on the cluster
        when one is set)."""
        client, where = cluster.client()
        ticket.send(self._boundaries_located, where)
        sets = boundaries.boundary_sets(req, live=lambda: ticket.live, client=client)
        try:
            for curves in sets:
                ticket.send(self._boundaries_shown, curves)
                if not ticket.live:
                    break
        except Exception as exc:     # a message under the legend, one log line
            log.warning("boundaries failed: %s: %s", type(exc).__name__, exc)
            ticket.send(self._boundaries_failed, cluster.failure_text(exc, client))
        finally:
            sets.close()
        ticket.finish()

    def _boundaries_located(self, where: str) -> None:
        """Where the curves under way are computed (as the map's status says it)."""
        self._boundary_where = where

    def _boundaries_shown(self, curves) -> None:
        self.overlay.show(curves, self._boundary_where)
        self.boundary_status.object = self.overlay.legend()
        if curves.complete and self.boundary_request is not None:
            self._on_curves(self.boundary_request, curves)
        self._cells_ready()

    def _cells_ready(self) -> None:
        """The curves went without the map's cells (not done then) and the map is done
        now: ask again with them (the branches' curves come from the shared cache).
        Called where either can happen last, both on the event loop."""
        shown = self.overlay.curves if self.overlay is not None else None
        if (shown is not None and shown.waiting and self._boundary_cells is not None
                and self._boundary_cells is self._cells and self._cells.filled):
            self._draw_boundaries(self.views[MAP].request.run, again=True)

    def _boundaries_failed(self, text: str) -> None:
        at = f" — {self._boundary_where}" if self._boundary_where else ""
        self.overlay.status = f"not computed — {text}{at}"
        self.boundary_status.object = self.overlay.legend()
