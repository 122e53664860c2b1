"""Bytes and text from disk: budgets on decompression, BOMs, and numeric text tables."""

from __future__ import annotations

import bz2
import gzip
import io as _stdio
import lzma
import warnings
import zlib
from pathlib import Path

import numpy as np

from planner.budget import memory_budget, require
from planner.errors import MapError

# Largest decompressed size a compressed text file may inflate to (None: a quarter of the
# memory budget of planner.budget, as the text and the parsed table follow the bytes).
# Inflation is streamed in chunks and stopped at the budget, so a small "zip bomb" never
# fills memory.
DECOMPRESSED_BUDGET = None
_CHUNK = 1 << 20
_BOM = b"\xef\xbb\xbf"


def check_file(p: Path) -> None:
    """Raise a one-line MapError unless ``p`` is an existing regular file."""
    if not p.is_file():
        raise MapError(f"{p}: file not found" if not p.exists() else f"{p}: not a regular file")


def read_bytes(p: Path) -> bytes:
    """Whole file as bytes (MapError on a missing, special or unreadable file)."""
    check_file(p)
    try:
        return p.read_bytes()
    except OSError as exc:
        raise MapError(f"{p.name}: cannot read file: {exc.strerror or exc}") from exc


def decompress(p: Path, compression: str, budget: int | None = None) -> bytes:
    """Inflate a ``.gz`` / ``.bz2`` / ``.xz`` file in chunks, refusing past ``budget`` bytes.

    Raises
    ------
    MapError
        Corrupt or truncated data, or more than ``budget`` (default
        :data:`DECOMPRESSED_BUDGET`) bytes once inflated.
    """
    check_file(p)
    limit = budget if budget is not None else DECOMPRESSED_BUDGET
    limit = memory_budget() // 4 if limit is None else int(limit)
    out = bytearray()

    def grow(chunk: bytes) -> None:
        out.extend(chunk)
        if len(out) > limit:
            raise MapError(f"{p.name}: decompresses to more than {limit} bytes (the "
                           "decompression budget, by default a quarter of the memory "
                           "budget: --memory-budget); refusing to inflate it")

    try:
        if compression == ".gz":  # gzip's reader already rejects trailing garbage
            with gzip.open(p, "rb") as f:
                while chunk := f.read(_CHUNK):
                    grow(chunk)
        else:
            _inflate_streams(p, compression, limit, grow)
    except MapError:
        raise
    except (OSError, EOFError, ValueError, zlib.error, lzma.LZMAError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MapError(f"{p.name}: corrupt or truncated {compression} data ({msg})") from exc
    return bytes(out)


def _inflate_streams(p: Path, compression: str, limit: int, grow) -> None:
    """Every ``.bz2`` / ``.xz`` stream of ``p`` in turn, passed chunk by chunk to ``grow``.

    Python's own readers stop quietly at bytes after the last stream that do not start a
    new one; here they are an error, as is a stream cut short."""
    make = bz2.BZ2Decompressor if compression == ".bz2" else lzma.LZMADecompressor
    dec, streams = make(), 0
    with open(p, "rb") as f:
        pending = f.read(_CHUNK)
        while True:
            if dec.eof:
                streams += 1
                rest = dec.unused_data or f.read(_CHUNK)
                if not rest:
                    return
                dec, pending = make(), rest
                try:
                    grow(dec.decompress(pending, max_length=limit + 1))
                except (OSError, lzma.LZMAError, EOFError):
                    raise MapError(f"{p.name}: trailing data after the {compression[1:]} "
                                   f"stream (not another stream)") from None
                pending = b""
                continue
            if dec.needs_input:
                pending = pending or f.read(_CHUNK)
                if not pending:
                    raise MapError(f"{p.name}: truncated {compression[1:]} data (the stream "
                                   f"{streams + 1} ends early)")
            grow(dec.decompress(pending, max_length=limit + 1))
            pending = b""


def decode_text(data: bytes, name: str) -> str:
    """UTF-8 text, a leading byte-order mark dropped."""
    if data.startswith(_BOM):
        data = data[len(_BOM):]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise MapError(f"{name}: not a text file (invalid UTF-8)") from None


def read_text(p: Path, compression: str | None = None, budget: int | None = None) -> str:
    """A (possibly compressed) UTF-8 text file."""
    data = read_bytes(p) if compression is None else decompress(p, compression, budget)
    return decode_text(data, p.name)


def header_lines(data: bytes, name: str, what: str, end_key: str,
                 max_bytes: int = 1 << 20) -> tuple[list[str], int]:
    """ASCII header lines of a binary file up to and including the line starting ``end_key``.

    Returns the stripped lines (comments kept) and the offset of the byte after the last one.
    Any number of lines is accepted within the first ``max_bytes`` bytes.
    """
    lines = []
    pos = 0
    while pos < min(len(data), max_bytes):
        nl = data.find(b"\n", pos)
        if nl < 0:
            break
        line = data[pos:nl].decode("ascii", errors="replace").strip()
        if pos == 0 and line.startswith("\ufeff"):
            line = line[1:]
        pos = nl + 1
        lines.append(line)
        if line.split(" ", 1)[0].upper() == end_key.upper():
            return lines, pos
    raise MapError(f"{name}: {what} header has no '{end_key}' line")


_TEXT_PARSE_BYTES = 8  # per character of text parsed by loadtxt


def loadtxt(text: str, name: str, ncols: int, first_line: int = 1, exact: bool = False,
            usecols: tuple[int, ...] | None = None) -> np.ndarray:
    """Parse whitespace/comma separated numbers, '#' comments, as float64 (rows, ncols).

    ``exact`` requires exactly ``ncols`` columns per row; otherwise each row needs the
    ``usecols`` columns (default the first ``ncols``) and any other columns are ignored.
    ``first_line`` is the file line number of ``text``'s first line, for messages.
    """
    # parsing holds the text, numpy's copy of it (up to 4 bytes a character) and its
    # chunks of numbers: refused over the budget before it starts, not by a MemoryError
    require(_TEXT_PARSE_BYTES * float(len(text)), f"{name}: parsing {len(text)} characters "
            f"of numbers")
    if text.startswith("\ufeff"):
        text = text[1:]
    if "," in text:
        text = text.replace(",", " ")
    cols = usecols if usecols is not None else tuple(range(ncols))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data": fine
            if exact:
                arr = np.loadtxt(_stdio.StringIO(text), dtype=np.float64, comments="#",
                                 ndmin=2)
            else:
                arr = np.loadtxt(_stdio.StringIO(text), dtype=np.float64, comments="#",
                                 ndmin=2, usecols=cols)
        ok = arr.size == 0 or arr.shape[1] == ncols
    except ValueError:
        ok = False
    if not ok:
        # numpy's row numbers skip comments and differ between its messages, so find the
        # offending line ourselves (error path only, speed irrelevant).
        raise MapError(f"{name}: {_describe_bad_line(text, ncols, exact, cols, first_line)}")
    return arr if arr.size else np.zeros((0, ncols))


def _describe_bad_line(text: str, ncols: int, exact: bool, cols: tuple[int, ...],
                       first_line: int) -> str:
    for i, raw in enumerate(text.splitlines()):
        tokens = raw.split("#", 1)[0].split()
        if not tokens:
            continue
        if exact and len(tokens) != ncols:
            bad = f"expected {ncols} numbers, got {len(tokens)}"
        elif len(tokens) <= max(cols):
            bad = f"expected at least {max(cols) + 1} numbers, got {len(tokens)}"
        else:
            try:
                [float(tokens[c]) for c in (range(ncols) if exact else cols)]
                continue
            except ValueError:
                bad = "not a number"
        return f"malformed line {i + first_line} ({bad}): {raw.strip()[:60]!r}"
    return "malformed numeric text"
