"""Plain scalar kernels compiled by numba when the optional `fast` extra is installed.

A kernel is written as scalar loops that numba compiles and that the caller's numpy version
reproduces operation for operation, so that both give the same numbers.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache


@lru_cache(maxsize=None)
def compiled(kernel: Callable) -> Callable | None:
    """`kernel` compiled by numba (cached on disk: later processes load it), or None when
    numba is not installed (the caller then runs its numpy version)."""
    try:
        import numba
    except ImportError:
        return None
    return numba.njit(cache=True, nogil=True)(kernel)
