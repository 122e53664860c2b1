"""Calling a compiled kernel without numba's per-call argument typing.

numba's dispatcher types every argument of every call to pick the compiled version. For a
kernel taking several ``NamedTuple`` structs that typing (done in Python for named tuples)
costs more than a short search itself; the engines call the compiled function directly
instead. numba has no public API for it: :func:`entry_point` reads
``dispatcher.overloads[signature].entry_point``, the one place the package relies on numba
internals. A compiled entry point does not check its arguments, so it must only get
arguments of the types it was looked up with: a caller keeps one entry point per argument
types (per world's structs, per :class:`planner.search.astar.bound.Bound` type).
A Ctrl-C that lands inside such a call surfaces as a SystemError caused by the
KeyboardInterrupt; the returned function raises the KeyboardInterrupt itself.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

__all__ = ["entry_point"]


def entry_point(disp, args: Sequence) -> Callable:
    """The compiled function of numba dispatcher ``disp`` for the types of ``args``
    (compiled, or loaded from the cache, if needed). Without numba compilation
    (``NUMBA_DISABLE_JIT``) the plain Python function."""
    if not hasattr(disp, "overloads"):
        return disp
    sig = tuple(disp.typeof_pyval(a) for a in args)
    if sig not in disp.overloads:
        disp.compile(sig)
    fn = disp.overloads[sig].entry_point

    def call(*a):
        try:
            return fn(*a)
        except SystemError as exc:  # Ctrl-C during the call arrives as the cause of this
            if isinstance(exc.__cause__, KeyboardInterrupt):
                raise KeyboardInterrupt from None
            raise

    return call
