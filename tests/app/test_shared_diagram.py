"""Diagrams shared between sessions (app.diagram.CACHE), without a browser.

The yardstick for "the same diagram" is one direct ``compute_chunk`` over all omega
values at once (no chunks, no cache, no sessions): every session must hold exactly its
impacts (every recorded one, not only those drawn), and the omega values computed in
total must be those of ONE diagram.
"""
import threading

import numpy as np
import pytest

from app import diagram, state
from app.explorer import Explorer

ARGS = {"bif_n": "24", "bif_min": "0.5", "bif_max": "4", "c": "0.07"}
DIRECT = diagram.compute_chunk          # not the counting one the fixture installs


@pytest.fixture
def counted(monkeypatch):
    """compute_chunk counting the omega values it computes, held at ``gate`` until the
    test opens it (so that a second session can arrive while the first computes)."""
    diagram.CACHE.clear()
    seen, gate = [], threading.Event()
    real = diagram.compute_chunk

    def compute_chunk(run, values, direction=0):
        assert gate.wait(30)
        seen.extend(values.tolist())
        return real(run, values, direction)

    monkeypatch.setattr(diagram, "compute_chunk", compute_chunk)
    yield seen, gate
    gate.set()
    diagram.CACHE.clear()


def _rows(d) -> list:
    return sorted(zip(np.round(d["omega"], 12), np.round(d["t"], 9), np.round(d["v"], 9)))


def points(view) -> list:
    """Every impact the session's diagram recorded: (omega, t, v), sorted."""
    return _rows(view.table())


def reference(args) -> list:
    run = state.validate(state.parse_query(args)[0])
    return _rows(DIRECT(run, diagram.sweep_values(run)))


def test_two_sessions_one_computation(counted):
    seen, gate = counted
    a = Explorer(args=ARGS)
    b = Explorer(args=ARGS)                   # arrives while a's diagram is in flight
    gate.set()
    assert a.diagram.job.done.wait(60) and b.diagram.job.done.wait(60)
    assert sorted(seen) == pytest.approx(np.linspace(0.5, 4, 24).tolist())   # once each
    ref = reference(ARGS)
    assert points(a.bifurcation) == ref and points(b.bifurcation) == ref
    assert a.diagram_status.object.startswith("complete")
    assert b.diagram_status.object.startswith("complete")


def test_a_finished_diagram_is_sent_at_once(counted):
    seen, gate = counted
    gate.set()
    a = Explorer(args=ARGS)
    assert a.diagram.job.done.wait(60)
    n = len(seen)
    b = Explorer(args=ARGS)
    assert b.diagram.job.done.is_set()             # no computation: streamed from the cache
    assert len(seen) == n and points(b.bifurcation) == points(a.bifurcation)
    assert b.diagram_status.object.startswith("complete")


def test_one_session_leaving_does_not_stop_the_others(counted):
    seen, gate = counted
    a = Explorer(args=ARGS)
    b = Explorer(args=ARGS)
    a.diagram.job.cancel()                         # a's tab closes mid-diagram
    gate.set()
    assert b.diagram.job.done.wait(60)
    assert points(b.bifurcation) == reference(ARGS)
    assert len(seen) == 24


def test_a_diagram_nobody_follows_stops(counted):
    seen, gate = counted
    a = Explorer(args=ARGS)
    key = a.run.diagram_key()
    a.diagram.job.cancel()
    gate.set()
    for _ in range(100):                      # the next chunk task sees it and stops
        if key not in diagram.CACHE:
            break
        threading.Event().wait(0.05)
    assert key not in diagram.CACHE
    assert len(seen) < 24


def test_finished_diagrams_stay_within_the_memory_bound(counted, monkeypatch):
    seen, gate = counted
    gate.set()
    small = diagram.DiagramCache(max_bytes=300_000, max_items=100)
    monkeypatch.setattr(diagram, "CACHE", small)
    keys, sizes = [], []
    for c in ("0.05", "0.06", "0.07", "0.08", "0.09", "0.1"):
        e = Explorer(args={**ARGS, "c": c})
        assert e.diagram.job.done.wait(60)
        keys.append(e.run.diagram_key())
    held = [k for k in keys if k in small]
    assert keys[-1] in held and len(held) < len(keys)     # the oldest went first
    assert held == keys[-len(held):]
    assert sum(small._items[k].nbytes for k in held) <= 300_000
