"""Run a function in a guarded worker process: hard timeout, crash status, dies with its
caller.

The worker is forked from a ``forkserver`` (modules preloaded once, so a call costs a fork,
not a fresh interpreter). It sends the function's result (a plain dict) through a pipe and
leaves with ``os._exit`` (no interpreter finalisation: native libraries with cyclic Python
callbacks report "leaked instances" at exit). Outcomes without a result:

* still running at the hard limit: killed, ``{"status": "timeout"}``;
* killed by a signal or segfaulting: ``{"status": "crashed", "reason": "worker crashed
  (signal N)"}``. The exit code is read before any liveness test: the forkserver reports a
  death late, and ``is_alive()`` said "running" for a dead worker (reported as a timeout);
* an exception in the function: ``{"status": "error"}``.

The worker never outlives its caller: it asks the kernel for SIGKILL when its parent (the
forkserver) dies (Linux ``PR_SET_PDEATHSIG``), a watchdog thread exits when the calling
process is gone (SIGKILL of the caller), and a Ctrl-C in the caller kills it at once.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import sys
import threading
import time
import types
from collections.abc import Callable, Sequence

_CTX: dict = {}


def _context(preload: Sequence[str], warm_env: str):
    """forkserver (preloading ``preload`` with ``warm_env=1`` set, so modules can warm up
    their kernels once for every worker) where available, else spawn."""
    key = (tuple(preload), warm_env)
    if key not in _CTX:
        if "forkserver" in mp.get_all_start_methods():
            from multiprocessing import forkserver

            ctx = mp.get_context("forkserver")
            ctx.set_forkserver_preload(list(preload))
            os.environ[warm_env] = "1"
            try:
                forkserver.ensure_running()
            finally:
                os.environ.pop(warm_env, None)
        else:  # pragma: no cover - non-POSIX
            ctx = mp.get_context("spawn")
        _CTX[key] = ctx
    return _CTX[key]


def run_guarded(func: Callable[..., dict], args: tuple, hard: float,
                preload: Sequence[str] = (), warm_env: str = "PLANNER_WORKER_WARM") -> dict:
    """``func(*args)`` in a worker process, killed after ``hard`` seconds.

    Returns
    -------
    dict
        The function's result, or ``{"status", "reason"}`` describing why there is none
        (module docstring). ``func`` must be importable by reference (a module-level
        function) and ``args`` picklable.
    """
    ctx = _context(preload, warm_env)
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_worker, args=(send, os.getpid(), func, args), daemon=True)
    # The child must not re-run the caller's script (spawn-style start methods import
    # ``__main__`` from its path): everything it runs lives in this package, so present a
    # bare ``__main__`` while the preparation data is taken. Callers then need no
    # ``if __name__ == "__main__"`` guard.
    main = sys.modules.get("__main__")
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        proc.start()
    finally:
        if main is not None:
            sys.modules["__main__"] = main
    send.close()  # so that recv sees EOF if the worker dies
    deadline = time.monotonic() + hard
    result = None
    timed_out = False
    try:
        while result is None:
            left = deadline - time.monotonic()
            if left <= 0:
                timed_out = True
                break
            if recv.poll(min(left, 0.5)):
                try:
                    result = recv.recv()
                except EOFError:  # the worker closed its end without a result: it died
                    break
            elif proc.exitcode is not None:
                break
    except BaseException:  # Ctrl-C in the caller: take the worker down with us
        proc.kill()
        proc.join()
        raise
    finally:
        recv.close()
    if result is not None:
        proc.join(5.0)
        if proc.exitcode is None:  # pragma: no cover - sent its result but did not exit
            proc.kill()
            proc.join()
        return result
    if not timed_out:  # died: wait for the exit status (the forkserver reports it late)
        proc.join(5.0)
    return _failure(proc, hard)


def _failure(proc, hard: float) -> dict:
    """Status and reason of a worker that gave no result, from its exit code first."""
    code = proc.exitcode
    if code is None:  # still running at the hard limit
        proc.kill()
        proc.join()
        return {"reason": f"timeout: worker killed after {hard:g} s", "status": "timeout"}
    if code < 0:
        return {"reason": f"worker crashed (signal {-code})", "status": "crashed"}
    return {"reason": f"worker crashed (exit code {code} without a result)",
            "status": "crashed"}


def _die_with(caller: int) -> None:
    """Make this worker exit when the caller (or the forkserver between) goes away."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - no prctl
            pass

    def watch() -> None:
        while True:
            time.sleep(0.2)
            try:
                os.kill(caller, 0)
            except (ProcessLookupError, PermissionError):  # gone (or its pid reused)
                os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


def _worker(conn, caller: int, func, args) -> None:
    """Worker body: run, send the result dict, leave without finalisation."""
    try:
        _die_with(caller)
        try:
            res = func(*args)
        except Exception as exc:  # report, not raise: the parent decides
            res = {"found": False, "reason": f"worker error: {type(exc).__name__}: {exc}",
                   "status": "error"}
        conn.send(res)
        conn.close()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
