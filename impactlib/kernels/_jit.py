"""The one jit decorator of the package (numba-stats style), and the two tuple helpers
the kernels use, which also run as plain Python (NUMBA_DISABLE_JIT)."""
import os

from numba import njit, types
from numba.cpython.unsafe.tuple import tuple_setitem
from numba.extending import overload
from numba.np.unsafe.ndarray import to_fixed_tuple

# NUMBA_DISABLE_JIT=1 runs the kernels as Python, for debugging; caching stays on otherwise.
jit = njit(cache=os.environ.get("IMPACTLIB_NO_CACHE") is None, nogil=True, error_model="numpy")


def as_tuple(a, n):
    """The first n items of the 1-D array ``a`` as a tuple (n a constant in jitted code):
    Numba passes a tuple by value, where an array argument costs reference counting."""
    return tuple(a[:n])


def with_item(t, i, value):
    """The tuple ``t`` with item i replaced by ``value`` (a tuple used as a small array
    that is never allocated)."""
    return t[:i] + (value,) + t[i + 1:]


@overload(as_tuple, prefer_literal=True)
def _as_tuple_jit(a, n):
    if isinstance(n, types.IntegerLiteral):
        return lambda a, n: to_fixed_tuple(a, n)


@overload(with_item)
def _with_item_jit(t, i, value):
    return lambda t, i, value: tuple_setitem(t, i, value)
