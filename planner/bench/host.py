"""The machine (and Dask worker) a suite row was run on, recorded in every row."""

from __future__ import annotations

import socket
import sys

__all__ = ["worker_host"]


def worker_host() -> dict:
    """Where this process runs: ``host`` (the machine's name) and ``worker`` (the Dask
    worker's address when the task runs on one, else None)."""
    worker = None
    if "distributed" in sys.modules:  # a Dask worker has it loaded; nobody else needs it
        from distributed import get_worker

        try:
            worker = get_worker().address
        except ValueError:  # not inside a worker
            pass
    return {"host": socket.gethostname(), "worker": worker}
