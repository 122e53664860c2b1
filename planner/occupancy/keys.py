"""Packing lattice indices into sortable int64 keys, and back; sets of keys.

3D: 21 bits per axis (indices in [-2**20, 2**20), about +-1 million cells per axis);
2D: 31 bits per axis. Keys sort lexicographically by (i, j, k), so a sorted key array is
also a sorted index list. Works inside numba kernels (``pack3``/``unpack3`` are jitted).
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.errors import MapError

BITS = {2: 31, 3: 21}
__all__ = ["BITS", "build_key_set", "check_range", "in_key_set", "in_key_set3", "index_limit",
           "mix64", "pack", "pack3", "step3", "unique_keys", "unpack", "unpack3"]

_EMPTY = -1  # empty slot of a key set


def index_limit(dim: int) -> int:
    """Indices must lie in ``[-limit, limit)`` on every axis to be packable."""
    return 1 << (BITS[dim] - 1)


def check_range(lo: np.ndarray, hi: np.ndarray, dim: int) -> None:
    """MapError unless every index between ``lo`` and ``hi`` (arrays of d-dimensional
    indices, e.g. a box's corners or ``(w, w)`` for an index list ``w``) is packable."""
    lim = index_limit(dim)
    if lo.min() < -lim or hi.max() >= lim:
        raise MapError(f"lattice indices exceed +-{lim} cells per axis; use a larger cell volume")


def pack(indices: np.ndarray) -> np.ndarray:
    """Pack (N, d) int64 indices into (N,) int64 keys; raises MapError when out of range."""
    w = np.asarray(indices, dtype=np.int64)
    if w.ndim != 2 or w.shape[1] not in BITS:
        raise MapError(f"indices must have shape (N, 2) or (N, 3), got {w.shape}")
    d = w.shape[1]
    bits, lim = BITS[d], index_limit(d)
    if len(w):
        check_range(w, w, d)
    key = np.zeros(len(w), dtype=np.int64)
    for j in range(d):
        key = (key << bits) | (w[:, j] + lim)
    return key


def unpack(keys: np.ndarray, dim: int) -> np.ndarray:
    """Inverse of :func:`pack`: (N,) int64 keys -> (N, dim) int64 indices."""
    k = np.asarray(keys, dtype=np.int64)
    bits, lim = BITS[dim], index_limit(dim)
    mask = (1 << bits) - 1
    out = np.empty((len(k), dim), dtype=np.int64)
    for j in range(dim - 1, -1, -1):
        out[:, j] = (k & mask) - lim
        k = k >> bits
    return out


# pack3's layout, pack's for d = 3: x in the top field, z in the lowest
_B3 = BITS[3]
_B2 = 2 * _B3
_L3 = 1 << (_B3 - 1)
_M3 = (1 << _B3) - 1


@njit_cached(_nrt=False)
def pack3(i, j, k):  # pragma: no cover - compiled
    """Key of one 3D index (no range check: callers stay inside the map's bounds)."""
    return (((i + _L3) << _B2) | ((j + _L3) << _B3)) | (k + _L3)


@njit_cached(_nrt=False)
def step3(d0, d1, d2):  # pragma: no cover - compiled
    """The key offset of an index step d: ``pack3(u + d) == pack3(u) + step3(d)`` while
    both indices stay in range (each field carries its own sign into the next)."""
    return (d0 << _B2) + (d1 << _B3) + d2


@njit_cached(_nrt=False)
def unpack3(key):  # pragma: no cover - compiled
    return ((key >> _B2) & _M3) - _L3, ((key >> _B3) & _M3) - _L3, (key & _M3) - _L3


def unique_keys(keys: np.ndarray) -> np.ndarray:
    """Sorted unique int64 keys. Sort + mask: numpy 2.x ``np.unique`` hashes first, which is
    slower on large key arrays. The stable sort finds sorted runs (keys here are mostly
    concatenated sorted lists), so it is fast on them and no slower on random keys."""
    k = np.sort(np.asarray(keys, dtype=np.int64), kind="stable")
    if len(k) < 2:
        return k
    keep = np.empty(len(k), dtype=bool)
    keep[0] = True
    np.not_equal(k[1:], k[:-1], out=keep[1:])
    return k[keep]


# -- hashing and key sets ------------------------------------------------------------------
@njit_cached(_nrt=False)
def mix64(key):  # pragma: no cover - compiled
    """splitmix64 finaliser: packed keys of neighbouring cells differ in few low bits."""
    x = np.uint64(key)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    x = x ^ (x >> np.uint64(31))
    return np.int64(x >> np.uint64(1))


@njit_cached
def build_key_set(keys, size):  # pragma: no cover - compiled
    """Open-addressing set of non-negative int64 keys; ``size`` a power of two >= 2 len."""
    table = np.full(size, _EMPTY, dtype=np.int64)
    mask = size - 1
    for i in range(keys.shape[0]):
        k = keys[i]
        p = mix64(k) & mask
        while table[p] != _EMPTY and table[p] != k:
            p = (p + 1) & mask
        table[p] = k
    return table


@njit_cached(_nrt=False)
def in_key_set(table, mask, k):  # pragma: no cover - compiled
    """Is key ``k`` in the open-addressing set ``table`` (size ``mask + 1``)?"""
    p = mix64(k) & mask
    while True:
        t = table[p]
        if t == k:
            return True
        if t == _EMPTY:
            return False
        p = (p + 1) & mask


@njit_cached(_nrt=False)
def in_key_set3(table, mask, i, j, k):  # pragma: no cover - compiled
    """Is the 3D index ``(i, j, k)``'s key in the set? False past :func:`pack3`'s range
    (``index_limit(3)`` each side of 0 per axis), where no stored cell is."""
    if i < -_L3 or i >= _L3 or j < -_L3 or j >= _L3 or k < -_L3 or k >= _L3:
        return False
    return in_key_set(table, mask, pack3(i, j, k))
