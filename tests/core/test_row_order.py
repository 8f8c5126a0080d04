"""The diagram merge's row order (sweeps.diagrams.row_order) is numpy's lexsort of every
row by (value index, up before down, time), whatever order the runs arrive in."""
import numpy as np
import pytest

from impactlib.sweeps.diagrams import row_order


def runs(rng, n_values, directions, shuffle=True):
    """Rows of runs (index, direction), each run's times ascending, runs in random order."""
    keys = [(i, d) for i in range(n_values) for d in directions]
    if shuffle:
        rng.shuffle(keys)
    idx, dr, t = [], [], []
    for i, d in keys:
        k = int(rng.integers(0, 6))
        idx += [i] * k
        dr += [d] * k
        t += sorted(rng.uniform(250.0, 500.0, k).round(1))   # ties inside a run too
    return np.array(idx), np.array(dr), np.array(t)


@pytest.mark.parametrize("directions", [(0,), (1, -1), (-1,)])
@pytest.mark.parametrize("seed", range(5))
def test_row_order_is_the_lexsort(directions, seed):
    rng = np.random.default_rng(seed)
    idx, dr, t = runs(rng, 40, directions)
    assert np.array_equal(row_order(idx, dr, t), np.lexsort((t, -dr, idx)))


def test_rows_not_in_runs_are_sorted_in_full():
    """A run whose times go back, and one run's rows in two places: the same order."""
    rng = np.random.default_rng(7)
    idx, dr, t = runs(rng, 30, (0,))
    back = t.copy()
    same = np.flatnonzero(idx[1:] == idx[:-1])
    back[same[0]], back[same[0] + 1] = back[same[0] + 1] + 1.0, back[same[0]]
    assert np.array_equal(row_order(idx, dr, back), np.lexsort((back, -dr, idx)))
    split = np.r_[idx, idx[:3]], np.r_[dr, dr[:3]], np.r_[t, t[:3] - 100.0]
    assert np.array_equal(row_order(*split), np.lexsort((split[2], -split[1], split[0])))
    assert row_order(np.zeros(0, int), np.zeros(0, int), np.zeros(0)).size == 0
