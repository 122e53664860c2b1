"""Calling a compiled kernel without numba's per-call argument typing.

numba's dispatcher types every argument of every call to pick the compiled version. For a
kernel taking several ``NamedTuple`` structs that typing (done in Python for named tuples)
costs more than a short search itself; the engines call the compiled function directly
instead. numba has no public API for it: :func:`entry_point` reads
``dispatcher.overloads[signature].entry_point``, the one place the package relies on numba
internals. A compiled entry point does not check its arguments, so it must only get
arguments of the types it was looked up with: a caller keeps one entry point per argument
types (per world's structs, per :class:`planner.search.astar.bound.Bound` type).
A signal whose Python handler raises (Ctrl-C's KeyboardInterrupt, a suite run's
``Interrupted``) while compiled code runs Python (numba unpickles a dtype to box a new array)
surfaces as a SystemError caused by the handler's exception; the returned function raises
that exception itself.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

__all__ = ["entry_point", "raw_entry_point", "signal_cause"]


def entry_point(disp, args: Sequence) -> Callable:
    """The compiled function of numba dispatcher ``disp`` for the types of ``args``
    (compiled, or loaded from the cache, if needed). Without numba compilation
    (``NUMBA_DISABLE_JIT``) the plain Python function."""
    fn = raw_entry_point(disp, args)
    if fn is disp:
        return fn

    def call(*a):
        try:
            return fn(*a)
        except SystemError as exc:  # a signal handler's exception arrives as the cause
            raise signal_cause(exc) from None

    return call


def raw_entry_point(disp, args: Sequence) -> Callable:
    """:func:`entry_point` without its wrapper, a Python call less for the hottest callers:
    they catch SystemError themselves and raise :func:`signal_cause` of it."""
    if not hasattr(disp, "overloads"):
        return disp
    sig = tuple(disp.typeof_pyval(a) for a in args)
    if sig not in disp.overloads:
        disp.compile(sig)
    return disp.overloads[sig].entry_point


def signal_cause(exc: SystemError) -> BaseException:
    """The exception to raise for a SystemError out of a compiled call: the signal
    handler's exception that caused it (module docstring), else ``exc`` itself."""
    return exc if exc.__cause__ is None else exc.__cause__
