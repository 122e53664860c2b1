"""One way to compile numba kernels: cached on disk where possible, in memory otherwise.

numba's ``cache=True`` needs a writable cache location (``__pycache__`` beside the source,
``NUMBA_CACHE_DIR`` or a user cache folder under HOME). On a read-only install with no
writable HOME it raises "no locator available" when the function is *defined*, which would
make ``import planner`` fail. :func:`njit_cached` falls back to compiling in memory.
"""

from __future__ import annotations

from collections.abc import Callable

from numba import njit

__all__ = ["njit_cached"]


def njit_cached(fn: Callable | None = None, **options) -> Callable:
    """``numba.njit(cache=True, **options)`` when numba can cache ``fn``, else without cache.

    Use as ``@njit_cached`` or ``@njit_cached(nogil=True)``.
    """
    def wrap(f: Callable) -> Callable:
        try:
            return njit(cache=True, **options)(f)
        except RuntimeError as exc:  # numba: "cannot cache function ...: no locator available"
            if "locator" not in str(exc):
                raise
            return njit(cache=False, **options)(f)

    return wrap if fn is None else wrap(fn)
