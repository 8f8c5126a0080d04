"""The app inside Jupyter (app.notebook): work runs on worker threads, results are applied
on the thread of the kernel's event loop, only when that loop runs, in the order sent.

A Jupyter kernel is an asyncio loop on the main thread that runs each cell; here
``asyncio.run`` plays the kernel and each coroutine step a cell."""
import asyncio
import threading
import time

import pytest

import impactlib as il
from app.jobs import KernelLoop
from app.notebook import explorer, settled

#: a small diagram keeps the session quick (as tests/app/conftest.py does)
SMALL = {"bif_n": "40", "bif_min": "0.5", "bif_max": "4"}




def test_results_are_applied_on_the_loop_thread_and_only_when_it_runs():
    async def cell():
        ex = explorer({**SMALL, "omega": "2.0"})
        await settled(ex, timeout=120)
        loop_thread = threading.current_thread()
        old = dict(ex.phase.source.data)
        assert ex.scene.label == "1-impact period-1"
        # who computes, who applies
        worked, applied, computed = [], [], threading.Event()
        work = ex.scene_job.work

        def recorded(run, ticket):
            out = work(run, ticket)
            worked.append(threading.current_thread())
            computed.set()
            return out
        ex.scene_job.work = recorded
        for view in (ex.phase, ex.displacement, ex.impact_map):
            view.source.on_change("data", lambda attr, o, n: applied.append(
                threading.current_thread()))

        ex.settings.omega = 3.0
        # the loop is blocked (a long synchronous cell): the worker finishes meanwhile,
        # but nothing of its result may reach the views from its thread
        assert computed.wait(60)
        time.sleep(0.2)
        assert applied == [] and ex.phase.source.data["x"] is old["x"]
        await settled(ex, timeout=120)
        return ex, loop_thread, worked, applied, old

    ex, loop_thread, worked, applied, old = asyncio.run(cell())
    assert worked and all(t is not loop_thread for t in worked)
    assert worked[0].name.startswith("impact-scene")
    assert applied and all(t is loop_thread for t in applied)
    # the views show omega = 3, classified independently of the app's scene job
    want = il.classify(il.simulate(il.Params(omega=3.0), t_end=ex.run.t_end,
                                   t_record=ex.run.t_record))
    assert ex.run.params.omega == 3.0 and ex.scene.label == want.label != "1-impact period-1"
    assert len(ex.phase.source.data["x"]) and ex.phase.source.data["x"] is not old["x"]


def test_kernel_loop_keeps_order_and_survives_a_failing_update():
    async def cell():
        loop = KernelLoop(asyncio.get_running_loop())
        out = []

        def send():
            for i in range(50):
                loop(lambda i=i: out.append((i, threading.current_thread())))
                if i == 10:
                    loop(lambda: 1 / 0)
        t = threading.Thread(target=send)
        t.start()
        t.join()
        assert out == [] and not loop.idle        # nothing ran on the sender's thread
        while not loop.idle:
            await asyncio.sleep(0.01)
        return out, threading.current_thread()

    out, main = asyncio.run(cell())
    assert [i for i, _ in out] == list(range(50))
    assert all(t is main for _, t in out)


def test_explorer_outside_a_running_loop_says_where_to_call_it():
    with pytest.raises(RuntimeError, match="Jupyter cell"):
        explorer()
