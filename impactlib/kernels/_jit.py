"""The one jit decorator of the package (numba-stats style)."""
import os

from numba import njit

# NUMBA_DISABLE_JIT=1 runs the kernels as Python, for debugging; caching stays on otherwise.
jit = njit(cache=os.environ.get("IMPACTLIB_NO_CACHE") is None, nogil=True, error_model="numpy")
