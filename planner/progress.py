"""Progress of a long command on stderr, with an ETA.

On a terminal one live line is redrawn: ``label [#####     ] done/total what  elapsed  eta``.
Elsewhere (a log file, CI) a line is printed at every tenth of the work and at least every
``every`` seconds, once the work has run ``quiet`` seconds (a short run stays silent), so a
log stays short and still shows a slow step is alive::

    with Progress(len(items), "queries", label="sampling") as bar:
        for item in items:
            work(item)
            bar.step()
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Callable, Iterator
from typing import TextIO

__all__ = ["Progress", "format_seconds"]


def format_seconds(s: float) -> str:
    """``42s``, ``3m05s`` or ``2h07m`` (``s`` in seconds, >= 0)."""
    s = max(0, int(round(s)))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


class Progress:
    """Counts ``total`` units of work (``what``: "runs", "queries", ...) on ``stream``
    (default stderr).

    ``enabled`` False prints nothing; ``clock`` returns seconds (tests pass a fake one);
    ``every`` is the longest silence in seconds when ``stream`` is not a terminal, and
    nothing is printed there before ``quiet`` seconds have passed.  The ETA is the elapsed
    time per unit done times the units left.
    """

    def __init__(self, total: int, what: str = "steps", *, label: str = "",
                 enabled: bool = True, stream: TextIO | None = None,
                 clock: Callable[[], float] = time.monotonic, every: float = 30.0,
                 quiet: float = 5.0):
        self.stream = stream if stream is not None else sys.stderr
        self.total, self.what, self.label = int(total), what, label
        self.enabled, self.clock, self.every, self.quiet = enabled, clock, every, quiet
        self.done = 0
        self.t0 = self.last = clock()
        self.tty = enabled and _isatty(self.stream)
        self.next_tenth = 1
        self._drawn = False

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def text(self) -> str:
        """``done/total what  elapsed  eta`` (the ETA once some work is done)."""
        el = self.clock() - self.t0
        frac = self.done / self.total if self.total > 0 else 1.0
        eta = f"eta {format_seconds(el / frac - el)}" if frac > 0 else "eta ?"
        head = f"{self.label} " if self.label else ""
        return f"{head}{self.done}/{self.total} {self.what}  {format_seconds(el)}  {eta}"

    def set_total(self, total: int) -> None:
        """A new estimate of the whole work (an exploration learns its length as it goes)."""
        self.total = int(total)

    @contextlib.contextmanager
    def paused(self) -> Iterator[None]:
        """Print other lines inside the block: the live line is cleared, then redrawn."""
        if self.tty and self._drawn:
            print("\r\033[K", end="", file=self.stream, flush=True)
            self._drawn = False
            yield
            self._draw()
        else:
            yield

    def step(self, k: int = 1) -> None:
        """``k`` more units are done."""
        self.done += k
        if not self.enabled:
            return
        frac = self.done / self.total if self.total > 0 else 1.0
        if self.tty:
            self._draw()
            return
        now = self.clock()
        if now - self.t0 < self.quiet:
            return
        if frac * 10 >= self.next_tenth or now - self.last >= self.every:
            self.next_tenth = int(frac * 10) + 1
            self.last = now
            print(f"progress {frac:4.0%}: {self.text()}", file=self.stream, flush=True)

    def _draw(self) -> None:
        frac = self.done / self.total if self.total > 0 else 1.0
        bar = "#" * int(30 * min(max(frac, 0.0), 1.0))
        print(f"\r[{bar:<30}] {self.text()}\033[K", end="", file=self.stream, flush=True)
        self._drawn = True

    def close(self) -> None:
        """End the live line on a terminal (a message printed next starts on its own line)."""
        if self.tty and self._drawn:
            print(file=self.stream, flush=True)
            self._drawn = False


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # closed or file-like without isatty
        return False
