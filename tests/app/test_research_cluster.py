"""The research views on a Dask cluster (app.cluster): with IMPACT_DASK_SCHEDULER naming a
scheduler, the regime map, the basins and the boundary curves are computed by its workers
and come out identical to the same pictures computed on the server's threads; a
scheduler that cannot be reached is said once in the log and on the status line, and
the pictures are computed here as without the setting."""
import logging

import numpy as np
import pytest

from app import boundaries, cluster
from app.research_panel import BASINS, MAP

distributed = pytest.importorskip("distributed")

# the scheduler always opens an HTTP server: a random local port keeps clusters apart
NO_DASHBOARD = dict(dashboard_address=None,
                    scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"})


class Finished(distributed.diagnostics.plugin.SchedulerPlugin):
    """Counts the tasks the scheduler saw finish, by the function's name."""

    def __init__(self):
        self.done: dict[str, int] = {}

    def transition(self, key, start, finish, *args, **kwargs):
        if finish == "memory" or finish == "erred":
            name = distributed.utils.key_split(key)
            self.done[name] = self.done.get(name, 0) + 1


@pytest.fixture(scope="module")
def scheduler():
    lc = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  **NO_DASHBOARD)
    plugin = Finished()
    lc.scheduler.add_plugin(plugin)
    try:
        yield lc, plugin
    finally:
        for c in list(cluster._SHARED.values()):
            c.close()
        cluster._SHARED.clear()
        lc.close()


@pytest.fixture
def few_seeds(monkeypatch):
    monkeypatch.setattr(boundaries, "SEEDS", 2)        # a quick boundary overlay
    boundaries.CACHE.clear()
    yield
    boundaries.CACHE.clear()


def pictures(make_explorer):
    """The regime map (with its boundary curves) and the basins of one session, computed
    as the page computes them (the research job; inline without a server)."""
    e = make_explorer(map_n="12", basins_n="10", boundaries="1", omega="2.62")
    boundaries.CACHE.clear()          # curves from scratch, not the shared set
    e.research.compute(MAP)
    assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(120)
    e.research.compute(BASINS)
    assert e.research.job.done.wait(120)
    views = e.research.views
    curves = e.research.overlay.curves
    m = views[MAP]
    # the map's cells as classify coded them: a class's colour (and which classes beyond
    # the palette share "other periodic") follows the order in which the blocks met it,
    # so it depends on where the blocks were cut, locally as on a cluster
    return dict(map=np.array(m.image), codes=(m.impacts, m.period),
                basins=np.array(views[BASINS].image),
                map_status=e.research.status[MAP].object,
                basins_status=e.research.status[BASINS].object,
                curves=[(b.kind, b.values) for b in curves.curves], complete=curves.complete,
                curves_status=e.research.overlay.status)


def test_research_views_on_a_cluster_equal_the_local_ones(make_explorer, scheduler,
                                                          few_seeds, monkeypatch):
    lc, finished = scheduler
    monkeypatch.delenv(cluster.ENV, raising=False)
    here = pictures(make_explorer)
    assert finished.done == {}
    monkeypatch.setenv(cluster.ENV, lc.scheduler_address)
    there = pictures(make_explorer)
    # the work ran on the cluster: map blocks, basins blocks, boundary curves
    assert finished.done.get("regime_task", 0) >= 2, finished.done
    assert finished.done.get("block", 0) >= 2, finished.done
    assert finished.done.get("boundary", 0) >= 1, finished.done
    where = f"on the Dask cluster at {lc.scheduler_address}"
    assert where in there["map_status"] and where in there["basins_status"]
    assert "Dask" not in here["map_status"] and "complete:" in here["map_status"]
    # the boundary curves' status says where they were computed, as the map's does
    assert there["curves_status"].endswith(f" — {where}"), there["curves_status"]
    assert "Dask" not in here["curves_status"] and "curves from" in here["curves_status"]
    # identical pictures: every cell's class, every start's attractor, every curve
    assert here["map"].shape == (12, 12) and len(np.unique(here["map"])) >= 2
    assert not np.isnan(there["map"]).any()
    for a, b in zip(there["codes"], here["codes"]):      # classify's (m, n) codes
        np.testing.assert_array_equal(a, b)
    assert here["basins"].shape == (10, 10) and len(np.unique(here["basins"])) >= 2
    np.testing.assert_array_equal(there["basins"], here["basins"])
    assert here["complete"] and there["complete"] and here["curves"]
    assert [k for k, _ in there["curves"]] == [k for k, _ in here["curves"]]
    for (_, a), (_, b) in zip(there["curves"], here["curves"]):
        np.testing.assert_array_equal(a, b)


def test_unreachable_scheduler_says_so_once_and_computes_here(make_explorer, monkeypatch,
                                                            caplog):
    monkeypatch.setenv(cluster.ENV, "tcp://127.0.0.1:9")        # nothing listens there
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 0.5)
    caplog.set_level(logging.INFO)
    try:
        e = make_explorer(map_n="6", basins_n="6")
        e.research.compute(MAP)
        assert e.research.job.done.wait(120)
        e.research.compute(MAP)                                  # a second picture
        assert e.research.job.done.wait(120)
        e.research.compute(BASINS)
        assert e.research.job.done.wait(120)
    finally:
        cluster._SHARED.pop("tcp://127.0.0.1:9", None)
    status = e.research.status[MAP].object
    assert status.startswith("complete: 6 rows"), status
    assert ("on this server (IMPACT_DASK_SCHEDULER='tcp://127.0.0.1:9': no Dask scheduler "
            "reached") in status
    assert "on this server (IMPACT_DASK_SCHEDULER" in e.research.status[BASINS].object
    image = np.array(e.research.views[MAP].image)
    assert image.shape == (6, 6) and (image >= 0).all()
    loud = [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert [r.name for r in loud] == ["app.cluster"], [r.getMessage() for r in loud]
    assert "IMPACT_DASK_SCHEDULER='tcp://127.0.0.1:9'" in loud[0].getMessage()


def test_without_the_dask_extra_the_message_names_it(monkeypatch):
    import builtins
    real = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name == "distributed":
            raise ImportError("no distributed")
        return real(name, *args, **kwargs)
    monkeypatch.setattr(builtins, "__import__", no_dask)
    client, error = cluster._connect("tcp://127.0.0.1:8786")
    assert client is None and "dask extra is not installed" in error


def test_a_scheduler_dying_mid_picture_says_so_and_the_next_picture_computes_here(
        make_explorer, few_seeds, monkeypatch, caplog):
    """The LocalCluster is closed while a regime map (with its boundary curves) is
    computed on it: that picture says in its view that the cluster stopped answering,
    the server log has no traceback (one WARNING line per failed picture, none from the
    app above WARNING), and another session's next picture is computed on this server
    with the note that the scheduler was not reached (the map complete, its cells those
    of a run on the server's threads)."""
    lc = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  **NO_DASHBOARD)
    address = lc.scheduler_address
    monkeypatch.setenv(cluster.ENV, address)
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 0.5)
    caplog.set_level(logging.INFO)
    try:
        e = make_explorer(map_n="40", boundaries="1")
        shown = e.research.rows

        def close_after_first_rows(kind, block):       # the cluster dies mid-picture
            shown(kind, block)
            if lc.status.name != "closed":
                lc.close()
        monkeypatch.setattr(e.research, "rows", close_after_first_rows)
        e.research.compute(MAP)
        assert e.research.job.done.wait(120) and e.research.boundary_job.done.wait(120)
        status = e.research.status[MAP].object
        assert status.startswith("not computed — the Dask cluster stopped answering "
                                 "during the picture"), status
        assert address in status
        assert 0 < e.research.views[MAP].rows_done < 40      # the rows that came stay
        curves = e.research.overlay.status
        assert ("the Dask cluster stopped answering" in curves
                or "curves from" in curves), curves            # failed (said so) or done
        # another session: its picture on this server, the cluster's absence noted
        other = make_explorer(map_n="8")
        other.research.compute(MAP)
        assert other.research.job.done.wait(120)
        status = other.research.status[MAP].object
        assert status.startswith("complete: 8 rows"), status
        assert f"on this server ({cluster.ENV}={address!r}: no Dask scheduler reached" in status
        monkeypatch.delenv(cluster.ENV)
        here = make_explorer(map_n="8")
        here.research.compute(MAP)
        assert here.research.job.done.wait(120)
        np.testing.assert_array_equal(other.research.views[MAP].impacts,
                                      here.research.views[MAP].impacts)
    finally:
        lc.close()
        for c in list(cluster._SHARED.values()):
            c.close()
        cluster._SHARED.clear()
    assert not [r for r in caplog.records if r.exc_info or "Traceback" in r.getMessage()]
    app_loud = [r for r in caplog.records
                if r.name.startswith("app") and r.levelno >= logging.WARNING]
    assert all(r.levelno == logging.WARNING for r in app_loud)
    assert any("map failed" in r.getMessage() for r in app_loud)
