"""The matcher's final continuous refinement: point-to-plane least squares on matched cells.

The discrete search ends on a pose quantized to a fraction of a cell, and its objective
(points in occupied cells) is flat inside a cell, so it cannot place a surface more finely
than a cell allows. The refinement works on the cells the source points land in: each
occupied reference cell with at least :data:`MIN_POINTS` points carries the mean of its
reference points and the normal of their local plane (the eigenvector of the smallest
eigenvalue of their covariance; a cell whose points are not planar, smallest eigenvalue
above a third of the middle one, is left out). The matcher uses the cells of the second
finest level (twice the finest side): on the finest cells (0.1 m by default) few points
and 2 cm of range noise give normals too noisy to fix the rotation (several times the
rotation error on geb079's simulated pairs); the experiment's ``default`` regime measures
the result. Gauss-Newton then minimises ``sum w_i (n_i . (R p_i + t - mu_i))^2`` over the
source points ``p_i`` (the source summarised per half cell, weighted by counts) whose cell
is occupied, looking the cells up again after every step (the matched cells move with the
pose), with a small Levenberg damping so that a direction no plane constrains (a corridor)
stays where the search left it.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner.lattice import Lattice, cosets
from planner.occupancy.keys import pack

__all__ = ["CellPlanes", "MIN_POINTS", "cell_planes", "refine"]

MIN_POINTS = 5  # points per cell for its own plane estimate
_DAMPING = 1e-6  # Levenberg term relative to the largest diagonal entry
_STEP_STOP = 1e-4  # m (and rad x source radius): a step this small ends the refinement


class CellPlanes(NamedTuple):
    """Planes of the occupied cells of one level (rows aligned with ``keys``).

    Attributes
    ----------
    keys : ndarray, shape (K,), int64
        Sorted packed keys of the planar occupied cells.
    means : ndarray, shape (K, 3)
        Mean of the reference points in each cell (m).
    normals : ndarray, shape (K, 3)
        Unit normal of each cell's plane.
    """

    keys: np.ndarray
    means: np.ndarray
    normals: np.ndarray


def _moments(points: np.ndarray, lattice: Lattice):
    keys, inv, counts = np.unique(pack(cosets.quantize(lattice, points)), return_inverse=True,
                                  return_counts=True)
    inv = inv.ravel()
    k = len(keys)
    mean = np.stack([np.bincount(inv, points[:, j], k) for j in range(3)], axis=1)
    mean /= counts[:, None]
    d = points - mean[inv]
    cov = np.empty((k, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            cov[:, a, b] = cov[:, b, a] = np.bincount(inv, d[:, a] * d[:, b], k)
    return keys, inv, counts, mean, cov / counts[:, None, None]


def cell_planes(points: np.ndarray, lattice: Lattice) -> CellPlanes:
    """The :class:`CellPlanes` of ``points`` ((N, 3), m) on the cells of ``lattice``: cells
    of at least :data:`MIN_POINTS` points that are planar (see the module)."""
    keys, _, counts, mean, cov = _moments(points, lattice)
    val, vec = np.linalg.eigh(cov)
    planar = (counts >= MIN_POINTS) & (val[:, 0] <= val[:, 1] / 3)
    return CellPlanes(keys[planar], np.ascontiguousarray(mean[planar]),
                      np.ascontiguousarray(vec[planar, :, 0]))


def refine(points: np.ndarray, weights: np.ndarray, planes: CellPlanes, lattice: Lattice,
           rot: np.ndarray, trans: np.ndarray, iterations: int = 10
           ) -> tuple[np.ndarray, np.ndarray, int]:
    """Gauss-Newton point-to-plane refinement of the pose ``rot`` (3, 3), ``trans`` (3,) m
    taking ``points`` ((N, 3), m, weighted by ``weights`` (N,)) onto the planes of the cells
    of ``lattice`` they fall in. Returns the pose and the number of steps taken."""
    r, t = rot.copy(), trans.copy()
    radius = max(float(np.sqrt(((points - points.mean(axis=0)) ** 2).sum(axis=1).mean())),
                 1e-9)
    steps = 0
    for _ in range(iterations):
        q = points @ r.T + t
        keys = pack(cosets.quantize(lattice, q))
        pos = np.minimum(np.searchsorted(planes.keys, keys), len(planes.keys) - 1)
        hit = planes.keys[pos] == keys if len(planes.keys) else np.zeros(len(q), bool)
        if hit.sum() < 6:
            break
        qh, w = q[hit], weights[hit]
        n, mu = planes.normals[pos[hit]], planes.means[pos[hit]]
        e = ((qh - mu) * n).sum(axis=1)
        jac = np.concatenate([np.cross(qh, n), n], axis=1)  # d e / d (omega, dt)
        h = jac.T @ (jac * w[:, None])
        g = jac.T @ (w * e)
        h += np.eye(6) * (_DAMPING * np.trace(h) / 6)
        x = -np.linalg.solve(h, g)
        w_rot, dt = x[:3], x[3:]
        ang = float(np.linalg.norm(w_rot))
        if ang > 0:
            k = w_rot / ang
            kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            dr = np.eye(3) + np.sin(ang) * kx + (1 - np.cos(ang)) * (kx @ kx)
        else:
            dr = np.eye(3)
        r, t = dr @ r, dr @ t + dt
        steps += 1
        if float(np.linalg.norm(dt)) + ang * radius < _STEP_STOP:
            break
    return r, t, steps
