import pytest

import impactlib as il
from app.explorer import Explorer

#: A small diagram keeps the app tests quick; the browser tests use the real default.
SMALL = {"bif_n": "40", "bif_min": "0.5", "bif_max": "4"}


@pytest.fixture(scope="session", autouse=True)
def _compiled_kernels():
    """Compile the kernels first, as scripts/app.sh and the container do before serving:
    a cold compile inside a session's first diagram would count against its time limit."""
    il.warmup()


@pytest.fixture
def make_explorer():
    made = []

    def make(**args):
        e = Explorer(args={**SMALL, **args})
        made.append(e)
        assert e.diagram.job.done.wait(60), "diagram did not finish"
        return e

    yield make
    for e in made:
        e.diagram.job.cancel()
