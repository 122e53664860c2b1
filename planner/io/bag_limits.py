"""Bag decompression with a limit: the chunks ``rosbags`` inflates (ROS 1 bz2 / lz4, mcap
lz4 / zstd, rosbag2 zstd messages and zstd-compressed files) are inflated by streaming
decompressors that stop past the decompression budget (a quarter of the memory budget, as
for compressed text maps) instead of allocating whatever a chunk declares or expands to.

``rosbags`` calls module-level names for these (``bz2_decompress`` and
``lz4_decompress`` in its ROS 1 reader, ``zstd`` and ``lz4_decompress`` in its mcap and
rosbag2 readers); :func:`limited_decompression` replaces them for the duration of one read
and restores them afterwards.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Iterator

from planner.budget import memory_budget
from planner.errors import MapError

__all__ = ["limited_decompression"]


def _too_big(name: str, limit: int) -> MapError:
    return MapError(f"{name}: a compressed bag chunk decompresses to more than {limit} bytes "
                    f"(the decompression budget, a quarter of the memory budget: "
                    f"--memory-budget); refusing to inflate it")


def _limited(make, name: str, limit: int):
    """``decompress(data) -> bytes`` through the streaming decompressor ``make()``, which
    takes ``max_length``; more than ``limit`` bytes out is refused."""
    def decompress(data, *_):
        out = make().decompress(data, max_length=limit + 1)
        if len(out) > limit:
            raise _too_big(name, limit)
        return out

    return decompress


class _LimitedReader:
    """A binary stream that refuses to yield more than ``limit`` bytes in total."""

    def __init__(self, raw, name: str, limit: int):
        self.raw, self.name, self.limit, self.n = raw, name, limit, 0

    def read(self, size: int = -1) -> bytes:
        room = self.limit + 1 - self.n  # >= 1: past the limit it has raised already
        data = self.raw.read(room if size is None or size < 0 else min(size, room))
        self.n += len(data)
        if self.n > self.limit:
            raise _too_big(self.name, self.limit)
        return data

    def readinto(self, b) -> int:
        data = self.read(len(b))
        b[:len(data)] = data
        return len(data)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.raw.close()

    def __getattr__(self, attr):
        return getattr(self.raw, attr)


class _Zstd:
    """The ``zstd`` module as ``rosbags`` uses it, with limited ``decompress`` and
    ``open`` (reading); everything else is the real module's."""

    def __init__(self, real, name: str, limit: int):
        self._real = real
        self.decompress = _limited(real.ZstdDecompressor, name, limit)
        self._name, self._limit = name, limit

    def open(self, file, mode: str = "rb", *args, **kwargs):
        f = self._real.open(file, mode, *args, **kwargs)
        return _LimitedReader(f, self._name, self._limit) if "r" in mode else f

    def __getattr__(self, attr):
        return getattr(self._real, attr)


@contextlib.contextmanager
def limited_decompression(name: str, limit: int | None = None) -> Iterator[None]:
    """Inside the block, every chunk ``rosbags`` decompresses is limited to ``limit`` bytes
    (default a quarter of the memory budget); past it, a one-line MapError naming ``name``.
    """
    import bz2

    limit = memory_budget() // 4 if limit is None else int(limit)
    saved = []

    def patch(module: str, attr: str, value) -> None:
        try:
            mod = importlib.import_module(module)
        except ImportError:  # an older or newer rosbags without that reader
            return
        if hasattr(mod, attr):
            saved.append((mod, attr, getattr(mod, attr)))
            setattr(mod, attr, value)

    try:
        import lz4.frame as lz4f
    except ImportError:  # pragma: no cover - lz4 comes with rosbags
        lz4f = None
    try:
        bz = _limited(bz2.BZ2Decompressor, name, limit)
        lz4 = _limited(lz4f.LZ4FrameDecompressor, name, limit) if lz4f is not None else None
        # the ROS 1 reader looks its decompressors up in a module-level table
        table = getattr(_module("rosbags.rosbag1.reader"), "decompressors", None)
        if isinstance(table, dict):
            for key, fn in (("bz2", bz), ("lz4", lz4)):
                if key in table and fn is not None:
                    saved.append((table, key, table[key]))
                    table[key] = fn
        if lz4 is not None:
            patch("rosbags.rosbag2.storage_mcap", "lz4_decompress", lz4)
        for module in ("rosbags.rosbag2.storage_mcap", "rosbags.rosbag2.reader"):
            real = getattr(_module(module), "zstd", None)
            if real is not None:
                patch(module, "zstd", _Zstd(real, name, limit))
        yield
    finally:
        for where, attr, value in reversed(saved):
            if isinstance(where, dict):
                where[attr] = value
            else:
                setattr(where, attr, value)


def _module(name: str):
    try:
        return importlib.import_module(name)
    except ImportError:
        return None
