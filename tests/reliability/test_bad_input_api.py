"""Bad input through the Python API and the command line: a ValueError (or a non-zero
exit) whose message names every bad field; valid-but-extreme input runs, bounded by the
work ceilings, with finite results. Never another exception."""
from __future__ import annotations

import math
import time

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import impactlib as il
from rel_cases import API_CEILING, api_cases, cli_cases, names_field, outcome

API = api_cases()
CLI = cli_cases()


def check(case):
    got = outcome(case.id)
    assert got.kind != "crash", f"{case.id} -> {got.message}"
    if case.fields:
        assert got.kind == "rejected", f"{case.id} was accepted: {got.message}"
        missing = [f for f in case.fields if not names_field(got.message, f)]
        assert not missing, f"{case.id}: message does not name {missing}: {got.message}"
    else:
        assert got.kind in ("runs", "partial"), f"{case.id}: {got.message}"
        assert "NON-FINITE" not in got.message, got.message
    return got


@pytest.mark.parametrize("case", API, ids=[c.id for c in API])
def test_api_input(case):
    check(case)


@pytest.mark.skipif(not CLI, reason="impactlib.cli is not there yet")
@pytest.mark.parametrize("case", CLI, ids=[c.id for c in CLI])
def test_cli_input(case):
    got = check(case)
    assert got.message.startswith("exit 2"), got.message       # argparse's usage error


def test_one_message_names_every_bad_field():
    with pytest.raises(ValueError) as exc:
        il.Params(m=-1.0, c=-1.0, k=math.nan, r=7.0, omega=0.0)
    for field in ("m", "c", "k", "r", "omega"):
        assert names_field(str(exc.value), field), (field, str(exc.value))


# -- fuzz: any float in any field --------------------------------------------------------

FIELDS = ("m", "c", "k", "g", "r", "omega")
RUN_FIELDS = ("t_end", "t_record", "x0", "v0", "phase")
ANY_FLOAT = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                      st.sampled_from([0.0, -0.0, 5e-324, 1e-300, 1e-12, 1e12, 1e300,
                                       -1e300, 2.0**-1074, 1.7976931348623157e308]))


def _checked_run(field, p, **kw):
    """simulate(): a ValueError naming ``field``, or a finite result within the ceiling."""
    tic = time.monotonic()
    try:
        sol = il.simulate(p, dense=64, **API_CEILING, **kw)
    except ValueError as exc:
        assert names_field(str(exc), field), (field, str(exc))
        return None
    elapsed = time.monotonic() - tic
    for name, arr in (("impacts.t", sol.impacts.t), ("impacts.v", sol.impacts.v),
                      ("poincare.x", sol.poincare.x), ("poincare.v", sol.poincare.v),
                      ("dense.x", sol.dense.x), ("dense.v", sol.dense.v)):
        assert np.all(np.isfinite(arr)), (p, kw, name)
    assert sol.status >= 0 and sol.message, (p, kw)
    # loose bound (not a benchmark): the work ceiling keeps a run far below this
    assert elapsed < 20, (p, kw, elapsed)
    return sol


@settings(settings.get_profile("reliability"))
@given(field=st.sampled_from(FIELDS), value=ANY_FLOAT)
def test_any_float_in_one_parameter(field, value):
    """One parameter anywhere on the float line, the others at the paper's values:
    a ValueError naming it, or a finite run (never ZeroDivisionError, OverflowError...)."""
    try:
        p = il.Params(**{field: value})
    except ValueError as exc:
        assert names_field(str(exc), field), str(exc)
        return
    _checked_run(field, p, t_end=50.0, t_record=25.0)


@settings(settings.get_profile("reliability"))
@given(field=st.sampled_from(RUN_FIELDS), value=ANY_FLOAT)
def test_any_float_in_one_run_setting(field, value):
    _checked_run(field, il.Params(), **{"t_end": 50.0, "t_record": 25.0, field: value})


def _log_uniform(lo, hi):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0 ** e)


@settings(settings.get_profile("reliability"))
@given(m=_log_uniform(1e-50, 1e50), c=st.one_of(st.just(0.0), _log_uniform(1e-50, 1e50)),
       k=st.one_of(st.just(0.0), _log_uniform(1e-50, 1e50)),
       g=st.one_of(st.just(0.0), _log_uniform(1e-50, 1e50), _log_uniform(1e-50, 1e50).map(
           lambda v: -v)),
       r=st.floats(0, 1), omega=_log_uniform(1e-50, 1e50))
def test_accepted_extremes_run_finite(m, c, k, g, r, omega):
    """Every combination Params accepts runs (or is rejected by simulate with a
    message) and gives finite numbers: no overflow inside the accepted range."""
    p = il.Params(m=m, c=c, k=k, g=g, r=r, omega=omega)
    _checked_run("omega", p, t_end=50.0, t_record=25.0)
