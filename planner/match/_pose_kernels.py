"""Compiled kernels of :class:`planner.match.pose_index.PoseIndex`: an open-addressing hash
map from a cell's packed key to the head of a linked list of the rows stored in that cell.

Slots hold the key (-1: empty) and the head row; ``nxt[row]`` is the next row of the same
cell (-1: the end), so an add writes two entries and never moves stored rows. A bitmap of
16 bits per slot answers most probes of empty cells without reading the table: one 64-bit
word per block of 4 x 4 x 4 cells (blocks hashed onto words), one bit per cell, so the
some 50 neighbouring cells a query that finds nothing probes read a few words instead of
50 scattered slots (at 1e6 cells the table is 32 MB, the bitmap 4 MB: fewer bits per slot
let more empty cells through to the table as false positives).
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.keys import BITS, index_limit, pack3, step3

_LIM = index_limit(3)  # packable index range per axis
_GOLD = np.uint64(0x9E3779B97F4A7C15)  # Fibonacci hashing
_MIX = np.uint64(0xD6E8FEB86659FD93)  # the bitmap's hash


_LOW = np.int64(step3(3, 3, 3))  # the low two bits of each axis's field of a key
_B3 = BITS[3]  # pack3's field of one axis
_B2 = 2 * _B3


@njit_cached(_nrt=False)
def _bit(key, shift):  # pragma: no cover - compiled
    """(word, bit) of ``key`` in a bitmap of 2**(64 - shift) words: one word per block of
    4 x 4 x 4 cells (hashed), one bit per cell of the block, so that the cells a query
    probes, neighbours of one another, share a few words."""
    block = key & ~_LOW
    local = (((key >> _B2) & 3) << 4) | (((key >> _B3) & 3) << 2) | (key & 3)
    word = np.int64((np.uint64(block) * _MIX) >> np.uint64(shift))
    return word, np.uint64(1) << np.uint64(local)


@njit_cached(_nrt=False)
def _slot(key, shift):  # pragma: no cover - compiled
    return np.int64((np.uint64(key) * _GOLD) >> np.uint64(shift))


@njit_cached(nogil=True)
def insert(tkeys, theads, bitmap, nxt, keys, first_row):  # pragma: no cover - compiled
    """Link rows ``first_row + i`` (keys[i]) into their cells; returns the cells created.
    The table (2**bits slots) must keep at least one empty slot per new key; ``bitmap``
    (uint64 words) holds 16 bits per slot."""
    mask = len(tkeys) - 1
    shift = 64 - int(np.log2(len(tkeys)))
    bshift = 64 - int(np.log2(len(bitmap)))
    created = 0
    for i in range(len(keys)):
        k = keys[i]
        s = _slot(k, shift)
        while tkeys[s] != -1 and tkeys[s] != k:
            s = (s + 1) & mask
        if tkeys[s] == -1:
            tkeys[s] = k
            theads[s] = -1
            created += 1
            word, bit = _bit(k, bshift)
            bitmap[word] |= bit
        row = first_row + i
        nxt[row] = theads[s]
        theads[s] = row
    return created


@njit_cached(nogil=True)
def rehash(tkeys, theads, new_keys, new_heads, new_bitmap):  # pragma: no cover - compiled
    """Move every cell of the table into the (empty, larger) one and its bitmap."""
    mask = len(new_keys) - 1
    shift = 64 - int(np.log2(len(new_keys)))
    bshift = 64 - int(np.log2(len(new_bitmap)))
    for s in range(len(tkeys)):
        k = tkeys[s]
        if k == -1:
            continue
        t = _slot(k, shift)
        while new_keys[t] != -1:
            t = (t + 1) & mask
        new_keys[t] = k
        new_heads[t] = theads[s]
        word, bit = _bit(k, bshift)
        new_bitmap[word] |= bit


@njit_cached(nogil=True)
def near(q, cells, offsets, pos, nxt, tkeys, theads, bitmap, r2, out):  # pragma: no cover
    """out[i]: whether some stored row of ``pos`` lies within sqrt(r2) of ``q[i]`` (m), looking
    at the cells ``cells[i] + offsets[j]`` (nearest first) and stopping at the first hit."""
    mask = len(tkeys) - 1
    shift = 64 - int(np.log2(len(tkeys)))
    bshift = 64 - int(np.log2(len(bitmap)))
    for i in range(q.shape[0]):
        x0, x1, x2 = q[i, 0], q[i, 1], q[i, 2]
        hit = False
        for j in range(offsets.shape[0]):
            w0 = cells[i, 0] + offsets[j, 0]
            w1 = cells[i, 1] + offsets[j, 1]
            w2 = cells[i, 2] + offsets[j, 2]
            if (w0 < -_LIM or w0 >= _LIM or w1 < -_LIM or w1 >= _LIM
                    or w2 < -_LIM or w2 >= _LIM):
                continue
            k = pack3(w0, w1, w2)
            word, bit = _bit(k, bshift)
            if not (bitmap[word] & bit):
                continue  # certainly no stored cell
            s = _slot(k, shift)
            while tkeys[s] != -1 and tkeys[s] != k:
                s = (s + 1) & mask
            if tkeys[s] == -1:
                continue
            row = theads[s]
            while row != -1:
                d0 = pos[row, 0] - x0
                d1 = pos[row, 1] - x1
                d2 = pos[row, 2] - x2
                if d0 * d0 + d1 * d1 + d2 * d2 <= r2:
                    hit = True
                    break
                row = nxt[row]
            if hit:
                break
        out[i] = hit
