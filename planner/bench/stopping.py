"""Stopping a suite run: SIGINT / SIGTERM become :class:`Interrupted`, and the worker
processes (and their own workers, such as OMPL's) are killed; finished rows are already on
disk."""

from __future__ import annotations

import contextlib
import signal
import time

from planner._interrupt import deferred

__all__ = ["Interrupted", "interruption", "signals_raise", "stop_processes", "worker_init"]


class Interrupted(Exception):
    """The run was stopped by SIGINT or SIGTERM; finished rows are saved."""

    def __init__(self, signum: int, processes: list | None = None):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum
        self.processes = processes or []  # every descendant when the signal came

    @property
    def exit_code(self) -> int:
        """128 + the signal number: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + self.signum


@contextlib.contextmanager
def signals_raise():
    """Turn SIGINT and SIGTERM into :class:`Interrupted` while the block runs; it leaves the
    block as :class:`Interrupted` even when it arrived inside a compiled call."""
    def handler(signum, frame):
        for s in (signal.SIGINT, signal.SIGTERM):  # a second signal must not interrupt cleanup
            signal.signal(s, signal.SIG_IGN)
        # the whole tree now: once the pool's workers die, their own children (an OMPL
        # worker) are re-parented and could no longer be found
        raise Interrupted(signum, _descendants())

    # deferred: not lost when it comes while a kernel compiles or loads (planner._interrupt)
    old = {s: signal.signal(s, deferred(handler)) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    except SystemError as exc:
        stop = interruption(exc)
        if stop is None:
            raise
        raise stop from None
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def interruption(exc: BaseException) -> Interrupted | None:
    """The :class:`Interrupted` that ``exc`` is or stands for, else None.

    When the handler runs inside a compiled call (numba runs Python to box a new array),
    numba reports the exception it left set as a SystemError caused by it.
    """
    if isinstance(exc, Interrupted):
        return exc
    if isinstance(exc, SystemError) and isinstance(exc.__cause__, Interrupted):
        return exc.__cause__
    return None


def _descendants() -> list:
    try:
        import psutil
    except ImportError:  # pragma: no cover - psutil comes with dask[distributed]
        return []
    out = []
    for p in psutil.Process().children(recursive=True):
        with contextlib.suppress(psutil.Error):
            # multiprocessing's resource tracker ends by itself with this process; killing it
            # makes it print a traceback
            if not any("resource_tracker" in part for part in p.cmdline()):
                out.append(p)
    return out


def stop_processes(processes: list, wait: float = 2.0) -> None:
    """Kill ``processes`` (psutil) and wait up to ``wait`` s until they are gone.

    SIGKILL, not SIGTERM: workers hold no output (every finished row is already on disk), and
    an OMPL worker forked by a forkserver prints a traceback when terminated.  Never reaps
    them (no ``wait()``): multiprocessing reaps its own workers, and a worker reaped behind
    its back looks alive to it forever.
    """
    import psutil

    def alive(p) -> bool:
        try:
            return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
        except psutil.Error:
            return False

    for p in processes:
        with contextlib.suppress(psutil.Error):
            p.kill()
    deadline = time.monotonic() + wait
    while time.monotonic() < deadline and any(alive(p) for p in processes):
        time.sleep(0.05)


def worker_init() -> None:
    """Workers leave signals to the parent, which stops them (a terminal's Ctrl-C reaches the
    whole process group)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
