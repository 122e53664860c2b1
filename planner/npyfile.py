"""Checked ``.npy`` reading: the header is read and checked before the array is allocated.

numpy's own reader trusts the header: a shape of ``(10**11, 3)`` is allocated before the
data turn out to be missing, and bytes after the array are ignored. :func:`read_array`
reads the header, refuses object dtypes (pickles), asks the memory budget for the declared
size, and then requires the data to fill the rest of the file exactly: fewer bytes are a
truncated file, more are trailing data.
"""

from __future__ import annotations

import io
import math
from typing import BinaryIO

import numpy as np

from planner.budget import require
from planner.errors import MapError, PlannerError

__all__ = ["read_array", "read_npy_file"]


def read_array(f: BinaryIO, size: int, name: str,
               error: type[PlannerError] = MapError) -> np.ndarray:
    """The array of a ``.npy`` stream ``f`` holding exactly ``size`` bytes.

    Parameters
    ----------
    f : binary file
        Positioned at the ``.npy`` magic string.
    size : int
        Bytes from the magic string to the end of the stream (file or zip member size).
    name : str
        What the error messages call the stream (e.g. ``"world.npz: blocked"``).
    error : type
        The exception raised.

    Returns
    -------
    ndarray
        Of the declared shape and dtype (C or Fortran order as stored).

    Raises
    ------
    PlannerError
        Bad magic or header, an object dtype, a declared size over the memory budget
        (``--memory-budget``), fewer bytes than declared, or bytes after the array.
    """
    fmt = np.lib.format
    try:
        version = fmt.read_magic(f)
        if version == (1, 0):
            shape, fortran, dtype = fmt.read_array_header_1_0(f)
        elif version in ((2, 0), (3, 0)):
            shape, fortran, dtype = fmt.read_array_header_2_0(f)
        else:
            raise ValueError(f"unsupported .npy version {version}")
    except (ValueError, EOFError, OSError, SyntaxError, TypeError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise error(f"{name}: not a valid .npy array ({msg})") from None
    if dtype.hasobject:
        raise error(f"{name}: .npy array holds Python objects (dtype {dtype}); refused")
    count = math.prod(shape)
    nbytes = float(count) * dtype.itemsize
    require(nbytes, f"{name}: its declared {shape} {dtype} array", error=error)
    data_size = size - f.tell()
    if nbytes > data_size:
        raise error(f"{name}: truncated .npy array: header declares {shape} {dtype} "
                    f"({int(nbytes)} bytes), the file holds {data_size}")
    if nbytes < data_size:
        raise error(f"{name}: {data_size - int(nbytes)} bytes of trailing data after the "
                    f".npy array")
    raw = bytearray(int(nbytes))  # writable, filled in place: no second copy
    view = memoryview(raw)
    got = 0
    while got < len(raw):
        n = f.readinto(view[got:])
        if not n:
            raise error(f"{name}: truncated .npy array")
        got += n
    arr = np.frombuffer(raw, dtype=dtype, count=count)
    return arr.reshape(shape, order="F" if fortran else "C")


def read_npy_file(path, name: str | None = None,
                  error: type[PlannerError] = MapError) -> np.ndarray:
    """:func:`read_array` of a whole ``.npy`` file at ``path`` (OSError -> ``error``)."""
    label = name or str(path)
    try:
        with open(path, "rb") as f:
            size = f.seek(0, io.SEEK_END)
            f.seek(0)
            return read_array(f, size, label, error)
    except OSError as exc:
        raise error(f"{label}: cannot read file: {exc.strerror or exc}") from None
