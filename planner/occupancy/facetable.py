"""The face table of a lattice's sight walk (:func:`planner.occupancy.facewalk.face_walk`):
from the Voronoi cell's geometry, each face (edge, vertex, facet) named by the set of facets
through it, with the cells around it and each one's facets through it; packed into one
float64 and one int64 array for the compiled walk."""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from planner.lattice import Lattice
from planner.occupancy.facestep import SLOTS

__all__ = ["FaceTable", "face_table"]

# Layout of a lattice's packed table (one float64 array ``fd`` and one int64 array ``fi``:
# few arguments, so a call of the walk costs little; R facets, NF faces, SM cells a face).
# The slots first, at fixed offsets (the walk's per-line set-up reads them slot by slot,
# with no indirection): one slot per pair of opposite facets (v_s = -v_r), the padding's
# zeros. fd: the pair's first facet w (3, SLOTS) at F_W, |w|^2 / 2 at F_H, |w|^2 / 2 +
# rho |w| at F_A (rho the covering radius: an exit time through +-w from a cell touching
# the segment d is at most 1 + this / |d . w|); then at F_REL the relevant vectors times
# the generator, rel @ G (R, 3) (c_u . v = (rel @ G) u for the cell at offset u), and
# w_j . w_k (SLOTS, SLOTS) at F_REL + 3R.
# fi: the header below; the slots' facets r and s (SLOTS,) each at I_SLOT, their bits
# 1 << r, 1 << s (0: padding) at I_SLOT + 2 SLOTS and w as index offsets (3, SLOTS) at
# I_SLOT + 4 SLOTS; then the face id of each facet set (2**R,; -1: no face) at
# fi[I_FMASK], the number of cells around each face (NF,) at fi[I_STARN], their offsets
# (NF, SM, 3) at fi[I_STAROFF] (the origin's cell first: the walk skips it), and each
# one's facets through the face (NF, SM; bit r: facet r) at fi[I_STARMASK].
I_R, I_NF, I_SM, I_REACH = 0, 1, 2, 3  # reach: |index - segment point| bound, 3 axes
I_FMASK, I_STARN, I_STAROFF, I_STARMASK, I_SLOT = 6, 7, 8, 9, 10
F_W, F_H, F_A, F_REL = 0, 3 * SLOTS, 4 * SLOTS, 5 * SLOTS


class FaceTable(NamedTuple):
    """A lattice's face table, packed (layout: the comments on ``I_*``)."""

    fd: np.ndarray  # float64
    fi: np.ndarray  # int64


def _active(x: np.ndarray, rel: np.ndarray, rhs: np.ndarray, tol: float) -> int:
    """Bit mask of the facets of the origin's cell through point ``x``."""
    s = rhs - rel @ x
    return int(sum(1 << r for r in np.flatnonzero(np.abs(s) <= tol * rhs)))


def face_table(lattice: Lattice) -> FaceTable:
    """The face table of a 3D lattice (a planar prism's too) from its Voronoi cell, packed
    into one float64 and one int64 array (layout: the comments on ``I_*``)."""
    g = np.asarray(lattice.generator, float)
    cell = lattice.voronoi
    rel = np.asarray(cell.relevant, float)
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    ginv = np.linalg.inv(g)
    verts = np.asarray(cell.vertices, float)
    e0, e1 = (np.asarray(e, float) for e in cell.edges)
    # Representative points: vertices, edge midpoints, facet centroids.
    pts = list(verts) + list(0.5 * (e0 + e1))
    vmask = [_active(v, rel, rhs, 1e-7) for v in verts]
    for r in range(len(rel)):
        on = [v for v, m in zip(verts, vmask, strict=True) if m >> r & 1]
        pts.append(np.mean(on, axis=0))
    # Candidate cells around a boundary point: every lattice point within twice the
    # covering radius (the cells touching the origin's, and more).
    span = int(np.ceil(2 * cell.covering_radius * np.abs(ginv).sum(axis=1).max())) + 1
    cand = np.array(list(itertools.product(range(-span, span + 1), repeat=3)), np.int64)
    cen = cand @ g.T
    cand = cand[np.linalg.norm(cen, axis=1) <= 2 * cell.covering_radius * (1 + 1e-9)]
    cen = cand @ g.T
    faces: dict[int, list] = {}
    for x in pts:
        m = _active(x, rel, rhs, 1e-7)
        if m == 0 or m in faces:
            continue
        d = np.linalg.norm(x - cen, axis=1)
        near = np.flatnonzero(np.abs(d - np.linalg.norm(x)) <= 1e-7 * cell.covering_radius)
        near = near[np.argsort(cand[near].any(axis=1), kind="stable")]  # the origin's first
        faces[m] = [(cand[k], _active(x - cen[k], rel, rhs, 1e-7)) for k in near]
    sm = max(len(s) for s in faces.values())
    nf = len(faces)
    fmask = np.full(1 << len(rel), -1, np.int64)
    star_n = np.zeros(nf, np.int64)
    star_off = np.zeros((nf, sm, 3), np.int64)
    star_mask = np.zeros((nf, sm), np.int64)
    for f, (m, star) in enumerate(faces.items()):
        fmask[m] = f
        star_n[f] = len(star)
        for j, (o, bm) in enumerate(star):
            star_off[f, j] = o
            star_mask[f, j] = bm
    ridx = np.rint(rel @ ginv.T).astype(np.int64)
    ext = np.abs(verts @ ginv.T).max(axis=0)
    reach = np.ceil(ext - 1e-9).astype(np.int64)
    nrel = len(rel)
    if not 2 <= nrel <= 2 * SLOTS - 2:
        raise ValueError(f"a 3D Voronoi cell has 6 to 14 facets, got {nrel}")
    pairs = np.array([(r, s) for r in range(nrel) for s in range(r + 1, nrel)
                      if np.allclose(rel[r], -rel[s], atol=1e-9 * np.abs(rel).max())], np.int64)
    if len(pairs) * 2 != nrel or len(pairs) > SLOTS:
        raise ValueError("a Voronoi cell's facets come in at most 8 opposite pairs")
    npair = len(pairs)
    first = pairs[:, 0]
    slot_f = np.zeros((5, SLOTS))
    slot_f[:3, :npair] = rel[first].T
    slot_f[3, :npair] = rhs[first]
    slot_f[4, :npair] = rhs[first] + cell.covering_radius * np.linalg.norm(rel[first], axis=1)
    gp = np.zeros((SLOTS, SLOTS))
    gp[:npair, :npair] = (rel @ rel.T)[np.ix_(first, first)]
    fd = np.concatenate([slot_f.ravel(), (rel @ g).ravel(), gp.ravel()])
    slot_i = np.zeros((7, SLOTS), np.int64)
    slot_i[0, :npair], slot_i[1, :npair] = pairs[:, 0], pairs[:, 1]
    slot_i[2, :npair], slot_i[3, :npair] = 1 << pairs[:, 0], 1 << pairs[:, 1]
    slot_i[4:, :npair] = ridx[first].T
    head = np.zeros(I_SLOT, np.int64)
    head[I_R], head[I_NF], head[I_SM] = nrel, nf, sm
    head[I_REACH:I_REACH + 3] = reach
    o = I_SLOT + slot_i.size
    head[I_FMASK] = o
    head[I_STARN] = o = o + len(fmask)
    head[I_STAROFF] = o = o + nf
    head[I_STARMASK] = o + 3 * nf * sm
    fi = np.concatenate([head, slot_i.ravel(), fmask, star_n, star_off.ravel(),
                         star_mask.ravel()])
    return FaceTable(np.ascontiguousarray(fd, float), np.ascontiguousarray(fi, np.int64))
