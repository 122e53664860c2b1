"""The one harness every script in ``benchmarks/`` measures with.

* Clocks: :func:`cpu` times a call by this thread's CPU time (``time.thread_time``: another
  process on a shared machine does not stretch it; the compiled kernels run on the calling
  thread). Scripts that time other processes use :func:`process_cpu` around them or the
  children's own report.
* Sides: :func:`interleaved` runs every side of a comparison on one item, then the next
  item, ``repeat`` rounds per item, and keeps each item's fastest round on each side (load
  on a shared machine slows whichever side it meets; the minimum filters it out).
* Statistics: :func:`ratio_line` prints the Hodges-Lehmann median of the paired per-item
  ratios (the median of the Walsh averages of their logs) with the 95% interval of the
  Wilcoxon signed-rank test that matches it (:func:`planner.analysis.stats.paired_ratio`).
  Every script prints at least one such line, starting with ``ratio``; the smoke test
  (``tests/test_benchmarks.py``) looks for it.
* Memory: :func:`peak_rss` is the process's resident high-water mark (Linux ``VmHWM``,
  reset by :func:`reset_peak_rss` through ``/proc/self/clear_refs``): everything the
  process touched, compiled kernels' arrays included. :func:`traced_peak` is
  ``tracemalloc``'s peak over one call: Python objects and numpy arrays allocated by
  Python code, not arrays allocated inside compiled (numba) code.
* Header: :func:`session` prints the machine (cores, CPU model, load average), Python,
  numpy, numba and scipy versions and the git commit at the start, and the load average
  again at the end, so a figure always comes with the conditions it was measured in.
* Smoke: :func:`add_arguments` gives every script ``--smoke`` (tiny sizes, a few seconds)
  and ``--data`` (the shared data folder, default ``../shared/data`` from the checkout).
* Figures as data: a script that takes ``--json PATH`` (:func:`add_arguments` with
  ``json=True``) passes it to :func:`session`; while the session is open every
  :func:`ratio_line` and :func:`single_ratio` keeps its figures, and :func:`record` keeps a
  table's, in a :class:`Record`, written to PATH (temp file + rename) with the header, the
  load at the end and the command line when the block ends without an error. The printed
  output is the same with or without it.

Reads only the package's public API.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import shlex
import sys
import time
import tracemalloc
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = (ROOT / ".." / "shared" / "data").resolve()

cpu_clock = time.thread_time  # this thread's CPU seconds


def add_arguments(ap: argparse.ArgumentParser, *, repeat: int | None = 3,
                  data: bool = False, json: bool = False) -> argparse.ArgumentParser:
    """Add the options every benchmark shares: ``--smoke``, and ``--repeat`` (rounds per
    item, best kept), ``--data`` and ``--json`` (the printed figures as data,
    :class:`Record`) when asked for."""
    ap.add_argument("--smoke", action="store_true",
                    help="tiny sizes, a few seconds: checks the script runs (figures "
                         "are not meaningful)")
    if repeat is not None:
        ap.add_argument("--repeat", type=int, default=repeat,
                        help=f"rounds per item on each side, interleaved; each item keeps "
                             f"its fastest (default {repeat})")
    if data:
        ap.add_argument("--data", type=Path, default=DATA,
                        help=f"the shared data folder (default {DATA})")
    if json:
        ap.add_argument("--json", type=Path, metavar="PATH",
                        help="also write the printed figures to this JSON file (written "
                             "when the run ends without an error)")
    return ap


@dataclass
class Record:
    """The figures one run printed, as data (``--json``).

    Attributes
    ----------
    title : str
        The header's title.
    command : str
        The command line that ran, as typed from the checkout's root.
    smoke : bool
        A smoke run (tiny sizes: figures not meaningful).
    header : list of str
        The header's machine, load and version lines (without the leading ``# ``).
    ratios : dict
        ``what`` of each :func:`ratio_line` -> ``median``, ``low``, ``high`` (None without
        an interval), ``overall``, ``n``, ``goal``, ``note``; of each :func:`single_ratio`
        -> ``value``, ``goal``, ``note``.
    figures : dict
        What :func:`record` kept (nested by its ``/``-separated keys).
    end : str
        The closing line (load average at the end, wall seconds).
    """

    title: str
    command: str
    smoke: bool
    header: list[str]
    ratios: dict[str, dict] = field(default_factory=dict)
    figures: dict[str, Any] = field(default_factory=dict)
    end: str = ""


_record: Record | None = None  # the open session's, when it was given a JSON path


def _plain(value: Any) -> Any:
    """``value`` with numpy scalars and arrays as Python numbers and lists (JSON), and
    non-finite floats as None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_plain(v) for v in value]
    if isinstance(value, np.integer | int) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, np.floating | float):
        return float(value) if math.isfinite(value) else None
    return value


def record(key: str, value: Any) -> None:
    """Keep ``value`` (a number, string or dict of them) under ``key`` (``"table/row"``:
    nested dicts) in the open session's :class:`Record`; nothing without one."""
    if _record is None:
        return
    *path, last = key.split("/")
    node = _record.figures
    for k in path:
        node = node.setdefault(k, {})
    node[last] = _plain(value)


def command_line(script: str, argv: Sequence[str] | None) -> str:
    """``python benchmarks/SCRIPT ARGS`` as typed (``argv`` None: this process's)."""
    args = sys.argv[1:] if argv is None else list(argv)
    return shlex.join(["python", f"benchmarks/{script}", *map(str, args)])


def cpu(fn: Callable[[], Any]) -> float:
    """Thread CPU seconds of one call of ``fn``."""
    t0 = cpu_clock()
    fn()
    return cpu_clock() - t0


def cpu_result(fn: Callable[[], Any]) -> tuple[Any, float]:
    """``fn()``'s result and its thread CPU seconds."""
    t0 = cpu_clock()
    out = fn()
    return out, cpu_clock() - t0


def process_cpu(fn: Callable[[], Any]) -> tuple[Any, float]:
    """``fn()``'s result and the CPU seconds of this process and its waited-for children
    over the call (for a call that runs a subprocess)."""
    t0 = os.times()
    out = fn()
    t1 = os.times()
    return out, (t1.user + t1.system + t1.children_user + t1.children_system
                 - t0.user - t0.system - t0.children_user - t0.children_system)


def best_of(fn: Callable[[], Any], repeat: int) -> float:
    """The fastest of ``repeat`` calls (thread CPU seconds)."""
    return min(cpu(fn) for _ in range(max(1, repeat)))


def median_of(fn: Callable[[], Any], repeat: int, clock: Callable[[], float] = cpu_clock
              ) -> float:
    """Median seconds per call of ``repeat`` calls, by ``clock`` (thread CPU by default;
    ``time.perf_counter`` for calls too short for the CPU clock's resolution)."""
    t = np.empty(max(1, repeat))
    for i in range(len(t)):
        t0 = clock()
        fn()
        t[i] = clock() - t0
    return float(np.median(t))


def interleaved(sides: dict[str, Callable[[Any], float]], items: Sequence, repeat: int
                ) -> dict[str, np.ndarray]:
    """Each item's fastest of ``repeat`` rounds on every side, the sides taking turns.

    Parameters
    ----------
    sides : dict name -> callable(item) -> seconds
        Each runs one item and returns the seconds it took (wrap with :func:`cpu` for the
        thread's CPU time, or return a time the side measured itself, e.g. a kernel's).
    items : sequence
        The queries, in order.
    repeat : int
        Rounds per item; each round runs every side once, in the order given.

    Returns
    -------
    dict name -> ndarray, shape (len(items),)
        Per item, the fastest round (seconds).
    """
    out = {k: np.full(len(items), math.inf) for k in sides}
    for i, item in enumerate(items):
        for _ in range(max(1, repeat)):
            for k, side in sides.items():
                out[k][i] = min(out[k][i], side(item))
    return out


@dataclass(frozen=True)
class Ratio:
    """A paired comparison: per-item ratios ``x / y`` summarised.

    Attributes
    ----------
    n : int
        Pairs used (both finite and positive).
    median, low, high : float
        Hodges-Lehmann median of the per-item ratios and its 95% interval (0 and inf when
        there are too few pairs for one).
    p : float
        Wilcoxon signed-rank p-value (NaN when it is undefined).
    total : float
        ``sum(x) / sum(y)``: the ratio of the totals (long items weigh more).
    """

    n: int
    median: float
    low: float
    high: float
    p: float
    total: float


def paired(x, y, seed: int = 0) -> Ratio:
    """Hodges-Lehmann median of the paired ratios ``x_i / y_i`` with its signed-rank
    interval (the package's :func:`planner.analysis.stats.paired_ratio`) and the ratio of
    the sums."""
    from planner.analysis.stats import paired_ratio

    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    s = paired_ratio(x, y, n_boot=2000, seed=seed)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    total = float(x[ok].sum() / y[ok].sum()) if ok.any() else math.nan
    return Ratio(s.n, s.estimate, s.low, s.high, s.p, total)


def ratio_line(what: str, x, y, *, goal: str = "", note: str = "",
               overall: float | None = None) -> str:
    """``ratio WHAT: median M [95% CI L, H], overall T, n N`` of the paired ``x / y``
    (one line, the form every script prints its ratios in; ``[no 95% CI: too few pairs]``
    under 6 pairs; ``goal`` e.g. ``">= 0.9"``).
    ``overall`` is ``sum(x) / sum(y)`` unless given (e.g. a ratio of rates over all
    items)."""
    r = paired(x, y)
    if r.n == 0:
        return f"ratio {what}: no pairs" + (f" ({note})" if note else "")
    total = r.total if overall is None else overall
    if _record is not None:
        ok = r.low > 0 and math.isfinite(r.high)
        _record.ratios[what] = _plain(dict(median=r.median, low=r.low if ok else None,
                                           high=r.high if ok else None, overall=total, n=r.n,
                                           goal=goal, note=note))
    # too few pairs for a 95% signed-rank interval (n < 6): the paired statistic returns
    # [0, inf], which reads like a measured range
    ci = (f"[95% CI {r.low:.3g}, {r.high:.3g}]" if r.low > 0 and math.isfinite(r.high)
          else "[no 95% CI: too few pairs]")
    line = f"ratio {what}: median {r.median:.3g} {ci}, overall {total:.3g}, n {r.n}"
    if goal:
        line += f" (goal {goal})"
    if note:
        line += f"; {note}"
    return line


def single_ratio(what: str, x: float, y: float, *, goal: str = "", note: str = "") -> str:
    """``ratio WHAT: R (x / y)`` for one pair of figures (each already a median or a best
    of N; say which in ``note``)."""
    line = f"ratio {what}: {x / y:.3g}" if y else f"ratio {what}: n/a (zero baseline)"
    if _record is not None:
        _record.ratios[what] = _plain(dict(value=x / y if y else None, goal=goal, note=note))
    if goal:
        line += f" (goal {goal})"
    if note:
        line += f"; {note}"
    return line


def peak_rss() -> int | None:
    """The process's peak resident memory (bytes; Linux ``VmHWM``), None without /proc."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def rss() -> int | None:
    """The process's resident memory now (bytes; ``VmRSS``), None without /proc."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def reset_peak_rss() -> bool:
    """Reset ``VmHWM`` to the current resident memory (``/proc/self/clear_refs``); False
    where that is not possible (the peak then includes what came before)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def traced_peak(fn: Callable[[], Any]) -> tuple[Any, int]:
    """``fn()``'s result and ``tracemalloc``'s peak bytes over the call (Python objects
    and numpy arrays made from Python; not what compiled code allocates itself)."""
    started = not tracemalloc.is_tracing()
    if started:
        tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    try:
        out = fn()
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        if started:
            tracemalloc.stop()
    return out, max(0, peak)


def _load() -> str:
    try:
        return ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "n/a"


def machine() -> list[str]:
    """The header's lines: machine, load, versions, commit."""
    from planner.analysis.metadata import run_metadata

    meta = run_metadata()
    pk = meta["packages"]
    versions = ", ".join(f"{k} {pk[k]}" for k in ("numpy", "numba", "scipy") if k in pk)
    return [f"machine: {meta['cpu']}, {meta['cpu_count']} cores; load average {_load()} "
            "(1, 5, 15 min)",
            f"Python {meta['python']}, {versions}; commit {meta['commit']}; {meta['date']}"]


@contextlib.contextmanager
def session(title: str, *, smoke: bool = False, stream=None, json: Path | None = None,
            command: str = "") -> Iterator[None]:
    """Print the header (title, machine, load, versions, commit) before the block and the
    load average after it.

    With ``json``, the block's ratio lines and :func:`record` figures are kept and written
    there (temp file + rename) as a :class:`Record` with the header and ``command`` (see
    :func:`command_line`) once the block ends without an error; nothing is written
    otherwise."""
    global _record
    from planner.fsutil import write_text_atomic

    out = stream if stream is not None else sys.stdout
    print(f"# {title}" + (" (smoke run: tiny sizes, figures not meaningful)" if smoke
                          else ""), file=out)
    header = machine()
    for line in header:
        print(f"# {line}", file=out)
    print(file=out, flush=True)
    rec = Record(title, command, smoke, header) if json is not None else None
    outer, _record = _record, rec
    t0 = time.perf_counter()
    ok = False
    try:
        yield
        ok = True
    finally:
        _record = outer
        end = f"load average at end {_load()}; {time.perf_counter() - t0:.1f} s wall"
        print(f"\n# {end}", file=out, flush=True)
        if rec is not None and ok:
            import json as json_module

            rec.end = end
            write_text_atomic(json, json_module.dumps(asdict(rec), indent=1) + "\n")


def skip(reason: str) -> int:
    """Print the one line a script prints when a prerequisite is absent; returns 0."""
    print(f"skipped: {reason}", flush=True)
    return 0
