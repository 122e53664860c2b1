"""The Voronoi cell of a lattice as a polytope, from its Voronoi-relevant vectors: vertices,
edges and the exact normalised second moment (metres; any dimension the callers use, 2 or 3).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

__all__ = ["cell_edges", "second_moment", "voronoi_vertices"]

# Relative tolerance for geometric ties (distances compared in units of the cell size).
TOL = 1e-9


def voronoi_vertices(rel: np.ndarray) -> np.ndarray:
    """Vertices of the Voronoi cell {x : x.v <= |v|^2/2 for every relevant v}; (n, d)."""
    d = rel.shape[1]
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    tol = TOL * float(rhs.max())
    found = []
    for idx in itertools.combinations(range(len(rel)), d):
        a = rel[list(idx)]
        if abs(np.linalg.det(a)) < 1e-12 * float(np.abs(a).max()) ** d:
            continue
        x = np.linalg.solve(a, rhs[list(idx)])
        if np.all(rel @ x <= rhs + tol * 10):
            found.append(x)
    pts = np.array(found)
    scale = math.sqrt(float(rhs.max()))
    _, keep = np.unique(np.round(pts / scale, 7), axis=0, return_index=True)
    return pts[np.sort(keep)]


def second_moment(rel: np.ndarray, verts: np.ndarray) -> float:
    """Exact normalised second moment of the Voronoi cell: (1/d) E|x|^2 / V^(2/d)."""
    d = rel.shape[1]
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    tol = 1e-7 * float(rhs.max())
    vol = 0.0
    inertia = 0.0
    for v, r in zip(rel, rhs, strict=True):
        on = verts[np.abs(verts @ v - r) < tol]
        if d == 2:
            # An edge of a polygon: triangle (0, a, b).
            a, b = on[0], on[1]
            area = abs(a[0] * b[1] - a[1] * b[0]) / 2
            vol += area
            inertia += area / 12 * (a @ a + b @ b + (a + b) @ (a + b))
            continue
        # A polygonal face: order vertices by angle about its centroid, fan into tetrahedra.
        c = on.mean(axis=0)
        n = v / np.linalg.norm(v)
        e1 = on[0] - c
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        ang = np.arctan2((on - c) @ e2, (on - c) @ e1)
        ring = on[np.argsort(ang)]
        for i in range(1, len(ring) - 1):
            a, b, cc = ring[0], ring[i], ring[i + 1]
            tv = abs(np.linalg.det(np.stack([a, b, cc]))) / 6
            s = a + b + cc
            vol += tv
            inertia += tv / 20 * (a @ a + b @ b + cc @ cc + s @ s)
    return inertia / vol / d / vol ** (2 / d)


def cell_edges(normals: np.ndarray, offsets: np.ndarray, verts: np.ndarray, d: int,
                scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Edges ``(e0, e1)`` of the cell: two vertices bound an edge iff they share d-1 facets."""
    on = np.abs(verts @ normals.T - offsets) < 1e-7 * scale  # (nv, k): vertex on facet
    shared = on.astype(np.int64) @ on.T.astype(np.int64)
    i, j = np.nonzero(np.triu(shared >= d - 1, k=1))
    return verts[i], verts[j]
