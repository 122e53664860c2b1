"""Output files of the commands, refused before any work when they cannot be written."""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

from planner.errors import PlannerError

PLOT_SUFFIXES = (".png", ".pdf", ".svg")
# (command, option) -> the suffixes it writes
OUTPUTS = {("plan", "out"): (".csv", ".json", ".tum"),
           ("world", "out"): (".npz", ".ply", ".bt"),
           ("view", "out"): (".html",), ("plan", "view"): (".html",),
           ("compare", "view"): (".html",), ("explore", "view"): (".html",),
           ("plan", "plot"): PLOT_SUFFIXES, ("compare", "plot"): PLOT_SUFFIXES,
           ("explore", "plot"): (".png",), ("explore", "gif"): (".gif",),
           ("match-experiment", "plot"): PLOT_SUFFIXES}


def check_output(option: str, text: str, suffixes: tuple[str, ...]) -> None:
    """Refuse an output file that cannot be written, before any work is done.

    Raises
    ------
    PlannerError
        Wrong suffix, a directory, or a folder that cannot be written into (one line).
    """
    p = Path(text)
    where = f"argument --{option}: {text}"
    if p.suffix.lower() not in suffixes:
        raise PlannerError(f"{where}: unsupported output type {p.suffix or '(none)'!r}; use "
                           f"{', '.join(suffixes)}")
    if p.is_dir():
        raise PlannerError(f"{where}: is a directory")
    parent = p.absolute().parent
    while not parent.exists():  # missing folders are created when writing
        parent = parent.parent
    if not parent.is_dir():
        raise PlannerError(f"{where}: {parent} is not a directory")
    try:  # a real probe: permissions, read-only and virtual file systems (/proc)
        fd, probe = tempfile.mkstemp(prefix=".planner-probe.", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise PlannerError(f"{where}: cannot write into {parent}: {exc.strerror}") from None


def check_sidecar(text: str) -> None:
    """Refuse ``--out X.csv`` when ``X.json`` (the path's metadata sidecar, a name the user
    did not give) exists and is not a sidecar this program wrote: it is never overwritten.

    Raises
    ------
    PlannerError
        One line naming both files.
    """
    import json

    side = Path(text).with_suffix(".json")
    if len(side.name.encode()) > 255:
        raise PlannerError(f"argument --out: {text}: its metadata sidecar {side.name} would "
                           f"be longer than 255 bytes; choose a shorter name")
    if not side.exists() and not side.is_symlink():
        return
    try:
        rec = json.loads(side.read_text(encoding="utf-8")) if side.is_file() else None
    except (OSError, ValueError, RecursionError):
        rec = None
    if not (isinstance(rec, dict) and "waypoint_columns" in rec and "path" in rec):
        raise PlannerError(f"argument --out: {text}: its metadata goes to {side}, which "
                           f"exists and is not a path sidecar written by planner; move it or "
                           f"choose another --out")


def check_outputs(a: argparse.Namespace) -> None:
    """:func:`check_output` for every output option of the command ``a.command``."""
    for (cmd, option), suffixes in OUTPUTS.items():
        if a.command == cmd and getattr(a, option, None):
            check_output(option, getattr(a, option), suffixes)
    if a.command == "plan" and (a.out or "").lower().endswith(".csv"):
        check_sidecar(a.out)
