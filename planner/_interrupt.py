"""Signal handlers whose exception is not lost while a kernel compiles or loads.

numba compiles kernels, and loads them from its cache, through llvmlite, whose code
generator calls back into Python (ctypes callbacks of its object cache). An exception
raised inside such a callback is printed and dropped: a Ctrl-C whose handler runs there
raises KeyboardInterrupt into nothing, and the program runs on to the end. :func:`deferred`
wraps a handler so that, called inside llvmlite, it sends the signal to the process again
a few milliseconds later instead of raising: once the callback has returned, the handler
raises where the exception propagates.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable
from types import FrameType

__all__ = ["deferred", "install_sigint", "install_sigterm", "Terminated"]

_NATIVE = "llvmlite"  # a frame of this package may sit in a C callback
_AGAIN = 0.005  # s until a deferred signal is sent again


def _in_native_callback(frame: FrameType | None) -> bool:
    while frame is not None:
        if _NATIVE in frame.f_code.co_filename:
            return True
        frame = frame.f_back
    return False


def deferred(handler: Callable) -> Callable:
    """``handler`` (a Python signal handler), sent again to the process when it would run
    inside llvmlite (module docstring)."""
    def run(signum: int, frame: FrameType | None):
        if _in_native_callback(frame):
            # sent again a little later, from a thread: raised now, it would run the
            # handler again before this one returns (and recurse); by then the callback
            # has mostly returned, else this repeats
            later = threading.Timer(_AGAIN, os.kill, (os.getpid(), signum))
            later.daemon = True
            later.start()
            return None
        return handler(signum, frame)

    return run


def install_sigint() -> None:
    """Make Ctrl-C raise KeyboardInterrupt through :func:`deferred` for the rest of the
    process. Nothing is changed outside the main thread, or when SIGINT is not handled by
    Python's default handler (a caller that installed its own, or ignores it)."""
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
        signal.signal(signal.SIGINT, deferred(signal.default_int_handler))


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C's KeyboardInterrupt so that the same clean-up runs
    (temporary files removed) and the program ends with 143."""


def _terminate(signum: int, frame: FrameType | None):
    raise Terminated()


def install_sigterm() -> None:
    """Make SIGTERM raise :class:`Terminated` (through :func:`deferred`) for the rest of the
    process, where it is handled by default (killing the process with no clean-up)."""
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL):
        signal.signal(signal.SIGTERM, deferred(_terminate))
