"""impactlib.sweeps.distributed on a LocalCluster: the same rows, in the same order, as the local
run.  One in-process cluster (two worker threads) serves the whole module."""
import numpy as np
import pytest

import impactlib as il
from impactlib.sweeps.diagrams import merge_regime_maps

distributed = pytest.importorskip("distributed")
ild = pytest.importorskip("impactlib.sweeps.distributed")

# short runs keep the module quick; the window still holds many forcing periods
RUN = dict(t_end=120.0, t_record=60.0)
P = il.Params()  # the paper's defaults: m=1, c=0.05, k=1, g=0, r=0.8, omega=2

# The scheduler always opens an HTTP server (port 8787 by default, even without the
# dashboard); a random local port keeps concurrent clusters on the machine apart.
NO_DASHBOARD = dict(dashboard_address=None,
                    scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"})

FIELDS = ("values", "param", "v", "t", "phase", "index", "direction", "status", "n_impacts")


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                       **NO_DASHBOARD)
    c = distributed.Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def assert_same_bifurcation(got, want):
    assert got.name == want.name
    for f in FIELDS:
        a, b = getattr(got, f), getattr(want, f)
        assert a.dtype == b.dtype, f
        # bit-identical: the same kernel on the same inputs, only scheduled elsewhere
        np.testing.assert_array_equal(a, b, err_msg=f)


@pytest.mark.parametrize("chunk", [None, 7, 1000])
def test_bifurcation_matches_local(client, chunk):
    values = np.linspace(0.5, 4.5, 61)
    want = il.bifurcation(P, "omega", values, **RUN)
    got = ild.bifurcation(client, P, "omega", values, chunk=chunk, **RUN)
    assert len(want) > 61   # every value impacts at least once in the window
    assert_same_bifurcation(got, want)


def test_bifurcation_unsorted_values_and_other_parameter(client):
    values = np.array([0.9, 0.2, 0.5, 0.95, 0.0, 0.7, 0.3])
    want = il.bifurcation(P.replace(omega=2.5), "r", values, **RUN)
    got = ild.bifurcation(client, P.replace(omega=2.5), "r", values, chunk=3, **RUN)
    assert_same_bifurcation(got, want)


def test_bifurcation_wall_position_starts_on_its_own_wall(client):
    values = np.linspace(-0.5, 0.5, 9)
    want = il.bifurcation(P, "g", values, **RUN)
    got = ild.bifurcation(client, P, "g", values, chunk=2, **RUN)
    assert_same_bifurcation(got, want)


@pytest.mark.parametrize("warm", ["up", "down", "both"])
def test_warm_start_matches_local(client, warm):
    values = np.linspace(3.0, 1.5, 13)
    want = il.bifurcation(P, "omega", values, warm_start=warm, **RUN)
    got = ild.bifurcation(client, P, "omega", values, warm_start=warm, **RUN)
    assert_same_bifurcation(got, want)
    if warm == "both":
        assert set(np.unique(got.direction)) == {-1, 1}


def test_rk4_method_passes_through(client):
    values = np.linspace(1.0, 3.0, 9)
    want = il.bifurcation(P, "omega", values, method="rk4", dt=0.01, **RUN)
    got = ild.bifurcation(client, P, "omega", values, method="rk4", dt=0.01, chunk=4, **RUN)
    assert_same_bifurcation(got, want)


@pytest.mark.parametrize("rows", [None, 1, 4])
def test_regime_map_matches_local(client, rows):
    wx = np.linspace(0.5, 4.5, 9)
    wy = np.linspace(0.1, 0.9, 6)
    want = il.regime_map(P, "omega", wx, "r", wy, **RUN)
    got = ild.regime_map(client, P, "omega", wx, "r", wy, rows_per_task=rows, **RUN)
    assert got.impacts.shape == (6, 9)
    for f in ("values_x", "values_y", "impacts", "period", "status"):
        np.testing.assert_array_equal(getattr(got, f), getattr(want, f), err_msg=f)
    assert (got.name_x, got.name_y) == ("omega", "r")
    assert got.label(0, 0) == want.label(0, 0)


def test_bad_arguments_fail_before_submitting(client):
    with pytest.raises(ValueError, match="'q' is unknown"):
        ild.bifurcation(client, P, "q", [1.0], **RUN)
    with pytest.raises(ValueError, match="chunk"):
        ild.bifurcation(client, P, "omega", [1.0], chunk=0, **RUN)
    with pytest.raises(ValueError, match="must be > 0"):
        ild.bifurcation(client, P, "omega", [1.0, -1.0], **RUN)
    with pytest.raises(ValueError, match="both 'r'"):
        ild.regime_map(client, P, "r", [0.5], "r", [0.5], **RUN)
    with pytest.raises(TypeError, match="Client"):
        ild.bifurcation(object(), P, "omega", [1.0], **RUN)


@pytest.mark.slow
def test_process_workers_match_local():
    """Two worker processes: tasks and results cross a real wire (pickled), each worker
    loads the kernels itself."""
    wx = np.linspace(0.5, 4.5, 21)
    wy = np.array([0.3, 0.6, 0.8])
    want_b = il.bifurcation(P, "omega", wx, **RUN)
    want_m = il.regime_map(P, "omega", wx, "r", wy, **RUN)
    want_s = il.basins(il.Params(r=0.8, omega=2.62), (0.0, 1.0), (-1.0, 1.0), n=(6, 6))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  **NO_DASHBOARD) as cluster, \
            distributed.Client(cluster) as c:
        got_b = ild.bifurcation(c, P, "omega", wx, chunk=5, **RUN)
        got_m = ild.regime_map(c, P, "omega", wx, "r", wy, rows_per_task=1, **RUN)
        got_s = ild.basins(c, il.Params(r=0.8, omega=2.62), (0.0, 1.0), (-1.0, 1.0),
                           n=(6, 6))
    assert_same_bifurcation(got_b, want_b)
    assert got_s == want_s
    for f in ("impacts", "period", "status"):
        np.testing.assert_array_equal(getattr(got_m, f), getattr(want_m, f), err_msg=f)


@pytest.mark.parametrize("warm_start", [False, "both"])
def test_bifurcation_with_lyapunov_matches_local(client, warm_start):
    values = np.linspace(2.0, 3.0, 23)
    want = il.bifurcation(P, "omega", values, lyapunov=True, warm_start=warm_start, **RUN)
    got = ild.bifurcation(client, P, "omega", values, chunk=5, lyapunov=True,
                          warm_start=warm_start, **RUN)
    assert_same_bifurcation(got, want)
    np.testing.assert_array_equal(got.lyapunov, want.lyapunov)
    assert np.isfinite(want.lyapunov).any()
    # the whole result, settings included, compares equal (timing aside)
    assert got == want


def test_regime_map_result_equals_local(client):
    vx, vy = np.linspace(1.0, 3.0, 6), np.linspace(0.3, 0.9, 4)
    want = il.regime_map(P, "omega", vx, "r", vy, **RUN)
    got = ild.regime_map(client, P, "omega", vx, "r", vy, rows_per_task=1, **RUN)
    assert got == want and got.settings() == want.settings()


# ---------------------------------------------------------------- basins

P262 = il.Params(r=0.8, omega=2.62)       # two coexisting periodic attractors


def test_basins_equal_local_cell_for_cell(client):
    want = il.basins(P262, (0.0, 1.0), (-1.0, 1.0), n=(11, 11))
    got = ild.basins(client, P262, (0.0, 1.0), (-1.0, 1.0), n=(11, 11))
    assert len(want.attractors) >= 2 and want.complete
    np.testing.assert_array_equal(got.labels, want.labels)
    np.testing.assert_array_equal(got.periods, want.periods)
    assert [a.label for a in got.attractors] == [a.label for a in want.attractors]
    for a, b in zip(got.attractors, want.attractors):
        np.testing.assert_array_equal(a.points, b.points)
    assert got == want and got.message == want.message


@pytest.mark.parametrize("rows", [1, 3])
def test_iter_basins_streams_the_local_blocks(client, rows):
    args = (P262, (0.0, 1.0), (-1.5, 1.5))
    kw = dict(n=(7, 9), rows_per_block=rows)
    want = list(il.iter_basins(*args, **kw))
    got = list(ild.iter_basins(client, *args, **kw))
    assert [b.start for b in got] == [b.start for b in want]
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g.labels, w.labels)
        np.testing.assert_array_equal(g.periods, w.periods)
        assert (g.rows_done, g.rows_total, g.message) == (w.rows_done, w.rows_total, w.message)


def test_basins_on_a_chaotic_attractor_label_every_cell_alike(client):
    """omega = 2.8 (the paper's Fig. 6): one chaotic attractor, found by the probes before
    any block starts, so the work per start matches as well."""
    want = il.basins(il.Params(omega=2.8), (0.0, 1.0), (-1.0, 1.0), n=(4, 4))
    got = ild.basins(client, il.Params(omega=2.8), (0.0, 1.0), (-1.0, 1.0), n=(4, 4))
    assert [a.kind for a in want.attractors] == ["chaotic"]
    np.testing.assert_array_equal(got.labels, want.labels)
    np.testing.assert_array_equal(got.periods, want.periods)


def test_basins_bad_arguments_fail_before_submitting(client):
    with pytest.raises(ValueError, match="x_range"):
        ild.basins(client, P262, (0.0, -1.0), (-1.0, 1.0), n=(3, 3))
    with pytest.raises(ValueError, match="n="):
        ild.iter_basins(client, P262, (0.0, 1.0), (-1.0, 1.0), n=(0, 3))
    with pytest.raises(TypeError, match="Client"):
        ild.basins(object(), P262, (0.0, 1.0), (-1.0, 1.0))



@pytest.mark.parametrize("rows", [None, 2])
def test_iter_regime_map_blocks_make_the_local_map(client, rows):
    vx, vy = np.linspace(0.5, 4.5, 7), np.linspace(0.1, 0.9, 5)
    want = il.regime_map(P, "omega", vx, "r", vy, **RUN)
    parts = list(ild.iter_regime_map(client, P, "omega", vx, "r", vy, rows_per_task=rows,
                                     **RUN))
    if rows == 2:
        assert [rm.values_y.size for rm in parts] == [2, 2, 1]
    assert merge_regime_maps(parts) == want


def test_iter_regime_map_validates_before_submitting(client):
    with pytest.raises(ValueError, match="both 'r'"):
        ild.iter_regime_map(client, P, "r", [0.5], "r", [0.5], **RUN)
    with pytest.raises(ValueError, match="rows_per_task"):
        ild.iter_regime_map(client, P, "omega", [1.0], "r", [0.5], rows_per_task=0, **RUN)
