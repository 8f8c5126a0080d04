"""The Lyapunov strip's y ticks (``app.views.lyapunov.strip_ticks``): 0 and at most one
round value each side, far enough apart for a strip ~60 px high."""
import math

import pytest

from app.views.lyapunov import strip_ticks


@pytest.mark.parametrize("lo, hi, expected", [
    # worked by hand: 90 % of each side, floored to 1, 2 or 5 times a power of ten
    (-0.25, 0.31, [-0.2, 0.0, 0.2]),       # 0.225 -> 0.2, 0.279 -> 0.2
    (-0.1, 0.1, [-0.05, 0.0, 0.05]),       # 0.09 -> 0.05, a quarter of the span 0.2
    (-0.15, 2.0, [0.0, 1.0]),              # 0.135 -> 0.1 < 0.25 * 2.15: left out
    (-3.0, 0.05, [-2.0, 0.0]),             # 2.7 -> 2; 0.045 -> 0.02 too close to 0
])
def test_ticks_worked_by_hand(lo, hi, expected):
    assert strip_ticks(lo, hi) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("lo, hi", [(-0.056, 0.056), (-0.4, 0.07), (-1e-3, 7.3), (-12.0, 3.0)])
def test_ticks_are_round_inside_and_apart(lo, hi):
    ticks = strip_ticks(lo, hi)
    assert 0.0 in ticks and len(ticks) <= 3
    for t in (t for t in ticks if t):
        assert lo < t < hi
        mantissa = abs(t) / 10.0 ** math.floor(math.log10(abs(t)))
        assert min(abs(mantissa - m) for m in (1, 2, 5)) < 1e-9
        assert abs(t) >= 0.25 * (hi - lo)
