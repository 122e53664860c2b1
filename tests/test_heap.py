"""The search's indexed 4-ary heap (planner.search._heap) against heapq."""

from __future__ import annotations

import heapq

import numpy as np
import pytest

from planner.search import _heap as H


def _heap(cap=64):
    return H.new_heap(cap), np.full(cap, -2, np.int64)


def _drain(h, pos, n):
    out = []
    while n:
        s, n = H.pop(h, pos, n)
        out.append(int(s))
    return out


def test_pops_in_key_order():
    h, pos = _heap()
    n = 0
    for slot, f in enumerate([5.0, 1.0, 4.0, 2.0, 3.0]):
        n = H.push(h, pos, n, slot, f, 0.0)
    assert _drain(h, pos, n) == [1, 3, 4, 2, 0]


def test_equal_keys_pop_larger_g_first():
    h, pos = _heap()
    n = 0
    for slot, g in enumerate([1.0, 3.0, 2.0]):
        n = H.push(h, pos, n, slot, 7.0, g)
    n = H.push(h, pos, n, 3, 6.5, 0.0)
    assert _drain(h, pos, n) == [3, 1, 2, 0]


def test_decrease_key_moves_entry_forward_and_positions_stay_exact():
    h, pos = _heap()
    n = 0
    for slot in range(10):
        n = H.push(h, pos, n, slot, 10.0 + slot, 0.0)
    H.decrease_key(h, pos, 9, 0.5, 0.0)
    H.decrease_key(h, pos, 5, 10.5, 0.0)
    for i in range(n):  # every held slot knows where it is
        assert pos[h.slot[i]] == i
    assert _drain(h, pos, n) == [9, 0, 5, 1, 2, 3, 4, 6, 7, 8]


@pytest.mark.parametrize("seed", range(5))
def test_matches_heapq_on_random_sequences(seed):
    """Random push / pop / decrease-key with many ties: the popped (f, g) keys equal those
    of a heapq reference keyed on (f, -g) with lazy deletion."""
    rng = np.random.default_rng(seed)
    cap = 2000
    h, pos = _heap(cap)
    n = 0
    ref: list = []
    key: dict[int, tuple[float, float]] = {}
    nxt = 0
    got, want = [], []
    for _ in range(3000):
        op = rng.random()
        if (op < 0.45 or not key) and nxt < cap:
            f, g = float(rng.integers(0, 20)), float(rng.integers(0, 4))
            n = H.push(h, pos, n, nxt, f, g)
            key[nxt] = (f, g)
            heapq.heappush(ref, (f, -g, nxt))
            nxt += 1
        elif op < 0.75 and key:
            while key.get(ref[0][2]) != (ref[0][0], -ref[0][1]):  # stale (lazy deletion)
                heapq.heappop(ref)
            want.append((ref[0][0], -ref[0][1]))
            s, n = H.pop(h, pos, n)
            pos[s] = -1
            got.append(key.pop(int(s)))
        elif key:
            x = int(rng.choice(list(key)))
            f, g = key[x]
            nf = f - float(rng.integers(0, 5))
            if nf < f:
                H.decrease_key(h, pos, x, nf, g)
                key[x] = (nf, g)
                heapq.heappush(ref, (nf, -g, x))
        assert n == len(key)
    assert got == want
    assert len(got) > 500


def test_remove_and_key_change_keep_positions_exact():
    h, pos = _heap()
    n = 0
    for slot in range(12):
        n = H.push(h, pos, n, slot, float(slot), 0.0)
    n = H.remove(h, pos, n, 0)  # the first entry
    n = H.remove(h, pos, n, 11)  # the last entry
    n = H.remove(h, pos, n, 5)
    H.change_key(h, pos, n, 3, 20.0, 0.0)  # up: to the back
    H.change_key(h, pos, n, 9, -1.0, 0.0)  # down: to the front
    assert pos[0] == pos[11] == pos[5] == -1
    for i in range(n):
        assert pos[h.slot[i]] == i
    assert _drain(h, pos, n) == [9, 1, 2, 4, 6, 7, 8, 10, 3]


@pytest.mark.parametrize("seed", range(5))
def test_remove_and_key_change_match_a_reference_on_random_sequences(seed):
    """Random push / pop / remove / key change (up and down) with many ties: every pop
    gives the key a sorted reference holds first, (f, -g) ascending."""
    rng = np.random.default_rng(100 + seed)
    cap = 1500
    h, pos = _heap(cap)
    n = 0
    key: dict[int, tuple[float, float]] = {}
    nxt = 0
    pops = removes = changes = 0
    for _ in range(3000):
        op = rng.random()
        if (op < 0.4 or not key) and nxt < cap:
            f, g = float(rng.integers(0, 20)), float(rng.integers(0, 4))
            n = H.push(h, pos, n, nxt, f, g)
            key[nxt] = (f, g)
            nxt += 1
        elif op < 0.6 and key:
            want = min((f, -g) for f, g in key.values())
            s, n = H.pop(h, pos, n)
            pos[s] = -1
            f, g = key.pop(int(s))
            assert (f, -g) == want
            pops += 1
        elif op < 0.8 and key:
            x = int(rng.choice(list(key)))
            n = H.remove(h, pos, n, x)
            del key[x]
            assert pos[x] == -1
            removes += 1
        elif key:
            x = int(rng.choice(list(key)))
            f, g = float(rng.integers(0, 20)), float(rng.integers(0, 4))
            H.change_key(h, pos, n, x, f, g)
            key[x] = (f, g)
            changes += 1
        assert n == len(key)
        assert sorted(int(s) for s in h.slot[:n]) == sorted(key)
    assert pops > 300 and removes > 300 and changes > 300


def _pq_positions_exact(h, pos, hn, sn):
    top = len(h.slot) - 1
    for i in range(hn):
        assert pos[h.slot[i]] == i
    for i in range(sn):
        assert pos[h.slot[top - i]] == H.SIDE - i


@pytest.mark.parametrize("seed", range(5))
def test_plateau_queue_pops_in_key_order_on_random_sequences(seed):
    """The A* queue (main heap + side heap of the f plateau, pq_*): random push / pop /
    decrease-key / flush with many ties, keys below the plateau included: every pop gives
    the key a sorted reference holds first, (f, -g) ascending, and every queued slot knows
    where it is in either part."""
    rng = np.random.default_rng(200 + seed)
    cap = 1200
    h, pos = _heap(cap)
    hn = sn = 0
    fcur = np.nan
    key: dict[int, tuple[float, float]] = {}
    nxt = 0
    pops = side_pops = flushes = 0
    for _ in range(4000):
        op = rng.random()
        if (op < 0.45 or not key) and nxt < cap:
            base = 10.0 if np.isnan(fcur) else fcur
            f = base + float(rng.choice([0, 0, 0, 1, 2, -1]))  # mostly on the plateau
            g = float(rng.integers(0, 6))
            hn, sn = H.pq_push(h, pos, hn, sn, fcur, nxt, f, g)
            key[nxt] = (f, g)
            nxt += 1
        elif op < 0.75 and key:
            want = min((f, -g) for f, g in key.values())
            side = sn > 0
            s, _, hn, sn2, fcur = H.pq_pop(h, pos, hn, sn, fcur)
            side_pops += side and sn2 < sn
            sn = sn2
            pos[s] = -1
            f, g = key.pop(int(s))
            assert (f, -g) == want
            pops += 1
        elif op < 0.97 and key:
            x = int(rng.choice(list(key)))
            f, g = key[x]
            nf = f - float(rng.choice([0, 0, 1]))
            ng = g - float(rng.integers(1, 3))
            hn, sn = H.pq_decrease(h, pos, hn, sn, fcur, x, nf, ng)
            key[x] = (nf, ng)
        else:
            hn = H.pq_flush(h, pos, hn, sn, fcur)
            sn = 0
            flushes += 1
        assert hn + sn == len(key)
        _pq_positions_exact(h, pos, hn, sn)
    assert pops > 500 and side_pops > 100 and flushes > 10


@pytest.mark.parametrize("cap", [4, 64, 4096])
def test_children_of_an_entry_share_a_cache_line_and_growing_keeps_entries(cap):
    h, pos = _heap(cap)
    for a in h:  # item 1 starts a line: children 4i+1 .. 4i+4 never straddle two lines
        assert a.flags.c_contiguous and a.flags.writeable and len(a) == cap
        assert (a.ctypes.data + a.itemsize) % 64 == 0
    n = 0
    for slot, f in enumerate([5.0, 1.0, 4.0, 2.0][:cap]):
        n = H.push(h, pos, n, slot, f, 0.0)
    g = H.grown_heap(h, 2 * cap, n)
    assert len(g.f) == 2 * cap and all((a.ctypes.data + a.itemsize) % 64 == 0 for a in g)
    assert _drain(g, pos, n) == _drain(h, pos.copy(), n)


def test_a_heap_past_a_long_search_size_pops_in_key_order():
    """A long search's heap (tens of thousands of entries: the sift-down's big-heap path)
    pops in (f, larger g) order and keeps every position exact."""
    cap = 40_000
    h, pos = _heap(cap)
    rng = np.random.default_rng(7)
    fs = rng.integers(0, 500, cap).astype(float)
    gs = rng.integers(0, 6, cap).astype(float)
    n = 0
    for slot in range(cap):
        n = H.push(h, pos, n, slot, fs[slot], gs[slot])
    assert all(pos[h.slot[i]] == i for i in range(n))
    order = _drain(h, pos, n)
    keys = [(fs[s], -gs[s]) for s in order]
    assert sorted(order) == list(range(cap)) and keys == sorted(keys)
