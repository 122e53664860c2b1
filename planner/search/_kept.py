"""Sight scratch kept between calls, one per walk (lattice) a thread or context works on.

Building a non-cubic walk's scratch (:func:`planner.search._los.new_scratch`) costs several
microseconds, a fair part of a short path's smoothing or a short any-angle search; a
caller that alternates between worlds (comparing lattices on one map, the benchmarks'
paired queries) would pay it on every call if it kept only its last. A :class:`Kept` store
keeps up to :data:`KEEP` scratches, each with the walk it was built for: holding the walk
keeps its ``id`` its own, so a scratch is never handed to another walk that reuses the id
(its arrays are sized for its own lattice).
"""

from __future__ import annotations

from typing import NamedTuple

from planner.search._los import SightScratch, new_scratch

__all__ = ["KEEP", "Kept", "kept_scratch"]

#: scratches a store keeps (the oldest goes first)
KEEP = 8


class Kept(NamedTuple):
    """A scratch built for ``walk`` and sight lines up to ``span`` m, and the last
    generation stamped in it (a reused scratch needs fresh stamps:
    :func:`planner.occupancy.walk.walk_on`)."""

    walk: object
    span: float
    sc: SightScratch
    gen: list[int]  # one element, updated in place by the caller


def kept_scratch(store: dict[int, Kept], walk, span: float) -> Kept:
    """The scratch in ``store`` for ``walk`` covering sight lines up to ``span`` m: the kept
    one, else a new one (kept in place of the walk's smaller one, or of the oldest entry
    when the store is full)."""
    k = store.get(id(walk))
    if k is not None and k.walk is walk and k.span >= span:
        return k
    store.pop(id(walk), None)
    if len(store) >= KEEP:
        del store[next(iter(store))]
    k = store[id(walk)] = Kept(walk, span, new_scratch(span, walk), [0])
    return k
