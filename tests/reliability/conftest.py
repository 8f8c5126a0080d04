"""Shared fixtures of the reliability tests: Hypothesis profiles, a served app.

Hypothesis profiles (applied per test with ``@settings(settings.get_profile(...))`` so
they never change other folders' tests): ``reliability`` (the default, modest for a
2-core CI) and ``reliability-thorough`` (RELIABILITY_PROFILE=thorough, for a longer
local run with fresh draws; the default is derandomized, tests/conftest.py).
"""
from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, Phase, settings

# no "explain" phase: it reruns a failing case hundreds of times (minutes on 2 cores)
_COMMON = dict(deadline=None, print_blob=True,
               phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.target, Phase.shrink],
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("reliability-ci", max_examples=50, **_COMMON)
settings.register_profile("reliability-thorough", max_examples=400, derandomize=False,
                          **_COMMON)
settings.register_profile(
    "reliability",
    settings.get_profile("reliability-thorough"
                         if os.environ.get("RELIABILITY_PROFILE") == "thorough"
                         else "reliability-ci"))


@pytest.fixture(scope="session")
def served():
    """The app served as a user serves it, on 127.0.0.1 (see rel_server.Served).

    Unused sessions are discarded after ~1 s (instead of Bokeh's 15-30 s), so memory
    checks after sessions close do not have to wait half a minute."""
    import impactlib as il
    from rel_server import Served

    # the kernels compiled first, as scripts/app.sh does before serving: a cold compile
    # inside the first session's diagram would count against its time limit
    il.warmup()
    srv = Served("served.log", extra_args=["--check-unused-sessions", "500",
                                           "--unused-session-lifetime", "1000"])
    yield srv
    srv.stop()
