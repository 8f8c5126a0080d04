"""The accuracy module's names, for callers that import them from here: impact matching
and error metrics live in :mod:`impactlib.compare` (numpy only), the accuracy report in
:mod:`impactlib.report` (loaded on first use of one of its names; needs the optional
extra ``report``)."""
from .compare import V_FLOOR, Comparison, impact_errors, match_impacts


def __getattr__(name):
    from . import report
    try:
        return getattr(report, name)
    except AttributeError:
        raise AttributeError(f"module 'impactlib.accuracy' has no attribute {name!r}") from None


__all__ = ["V_FLOOR", "Comparison", "impact_errors", "match_impacts"]
