"""Run ``planner`` command lines in forked child processes of one warm interpreter.

Each request (a JSON line on stdin: ``{"argv": [...], "limit": bytes, "timeout": s}``) is
run in a fresh child forked from this process, which imported the CLI and its heavy
modules once: the child sets its address-space limit, runs ``planner.cli.main(argv)`` as
``python -m planner`` would (an escaping exception prints its traceback and exits 1) and
exits. The parent answers one JSON line: ``{"rc": exit status or -signal or null after a
timeout (the child is then killed), "stdout": ..., "stderr": ..., "seconds": ...}``. A
crash, a hang or a memory blow-up stays in the child. Saves the ~1 s interpreter start of
every case.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import sys
import tempfile
import time
import traceback


def _child(argv: list[str], limit: int, out: int, err: int) -> None:
    os.dup2(out, 1)
    os.dup2(err, 2)
    sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115 - the child's own streams
    sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115
    rc = 1
    try:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        from planner.cli import main

        rc = main(argv)
    except SystemExit as exc:  # argparse errors and --help
        rc = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except BaseException:
        traceback.print_exc()
        rc = 1
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(rc if isinstance(rc, int) else 1)


def _run(argv: list[str], limit: int, timeout: float) -> dict:
    t0 = time.monotonic()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            _child(argv, limit, out.fileno(), err.fileno())
        deadline = time.monotonic() + timeout
        status = None
        while status is None:
            done, st = os.waitpid(pid, os.WNOHANG)
            if done:
                status = st
            elif time.monotonic() > deadline:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                break
            else:
                time.sleep(0.01)
        rc = None if status is None else os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return {"rc": rc, "stdout": out.read().decode(errors="replace"),
                "stderr": err.read().decode(errors="replace"),
                "seconds": time.monotonic() - t0}


def serve() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401 - warm: the bench and --plot import it

    import planner.analysis.compare  # noqa: F401
    import planner.bench.session  # noqa: F401
    import planner.cli  # noqa: F401
    import planner.planning  # noqa: F401

    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        print(json.dumps(_run(req["argv"], int(req["limit"]), float(req["timeout"]))),
              flush=True)


if __name__ == "__main__":
    serve()
