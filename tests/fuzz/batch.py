"""Run many ``planner`` command lines in this one process, under an address-space cap.

Started as ``python tests/fuzz/batch.py CAP_BYTES``: imports the CLI and its heavy modules
once, sets ``RLIMIT_AS`` to the cap, answers ``{"ready": true}``, then reads one JSON
request per line (``{"argv": [...], "fault": null | "enospc" | "eacces"}``) and answers
one JSON line per request: ``{"rc", "stdout", "stderr", "seconds", "maxrss"}``. Each
command runs as ``python -m planner`` would (``planner.cli.main``; an escaping exception
prints its traceback, exit status 1) with the environment, working folder and signal
handlers restored afterwards. ``fault`` makes every rename of an output (``os.replace``)
fail with that OS error, as a full disk or a read-only folder would at the last step.
The parent kills this process when a case takes too long and starts another for the rest.
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import resource
import signal
import sys
import time
import traceback

FAULTS = {"enospc": errno.ENOSPC, "eacces": errno.EACCES, "erofs": errno.EROFS}


def _run(argv: list[str], fault: str | None) -> dict:
    from planner.cli import main

    env, cwd = dict(os.environ), os.getcwd()
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    out, err = io.StringIO(), io.StringIO()
    real_replace = os.replace

    def failing_replace(src, dst, *a, **k):
        code = FAULTS[fault]
        raise OSError(code, os.strerror(code))

    t0 = time.monotonic()
    try:
        if fault:
            os.replace = failing_replace
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                rc = main(argv)
            except SystemExit as exc:  # argparse errors and --help
                rc = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            except BaseException:  # noqa: BLE001 - reported as python -m planner would
                traceback.print_exc()
                rc = 1
    finally:
        os.replace = real_replace
        os.environ.clear()
        os.environ.update(env)
        os.chdir(cwd)
        for s, h in handlers.items():
            signal.signal(s, h)
    return {"rc": rc, "stdout": out.getvalue()[-2000:], "stderr": err.getvalue()[-4000:],
            "seconds": time.monotonic() - t0,
            "maxrss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}


def serve(cap: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401 - warm: --plot and the bench import it

    import planner.analysis.compare  # noqa: F401
    import planner.api  # noqa: F401
    import planner.bench.session  # noqa: F401
    import planner.cli  # noqa: F401

    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    # replies on a private copy of stdout: a library writing to fd 1 cannot break them
    reply = os.fdopen(os.dup(1), "w")
    os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
    print(json.dumps({"ready": True}), file=reply, flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        print(json.dumps(_run(req["argv"], req.get("fault"))), file=reply, flush=True)


if __name__ == "__main__":
    serve(int(sys.argv[1]))
