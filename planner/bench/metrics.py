"""Path metrics against the raw obstacles (not the voxels): clearance and collision."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def _segment_point_dist(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Distances from points p (N, 3) to the segment a-b (metres)."""
    ab = b - a
    den = float(ab @ ab)
    t = np.zeros(len(p)) if den == 0 else np.clip((p - a) @ ab / den, 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * ab - p, axis=1)


def _segment_box_dist(a: np.ndarray, b: np.ndarray, c: np.ndarray, half) -> np.ndarray:
    """Distances from the segment a-b to axis-aligned cubes (centres c (N, 3), half edges
    (N, 1) or one for all, metres).

    The distance to a convex set along a segment is convex in the segment parameter, so
    a golden-section search converges to the exact minimum.
    """

    def dist(t: np.ndarray) -> np.ndarray:
        q = a + t[:, None] * (b - a)
        return np.linalg.norm(np.maximum(np.abs(q - c) - half, 0.0), axis=1)

    lo, hi = np.zeros(len(c)), np.ones(len(c))
    g = (np.sqrt(5) - 1) / 2
    for _ in range(60):
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        left = dist(m1) <= dist(m2)
        hi = np.where(left, m2, hi)
        lo = np.where(left, lo, m1)
    ends = np.minimum(dist(np.zeros(len(c))), dist(np.ones(len(c))))
    return np.minimum(dist((lo + hi) / 2), ends)


class Clearance:
    """Exact minimum distance from polylines to an obstacle set (points and cubes).

    Parameters
    ----------
    points : ndarray, shape (N, 3)
        Sensed obstacle points (m).
    boxes : ndarray, shape (M, 3)
        Centres of solid axis-aligned cubes (m).
    box_sizes : float or ndarray, shape (M,)
        Their edges (m): one for all, or each its own (OctoMap leaves).
    """

    def __init__(self, points: np.ndarray, boxes: np.ndarray, box_sizes=0.0):
        self.points = np.asarray(points, dtype=float).reshape(-1, 3)
        self.boxes = np.asarray(boxes, dtype=float).reshape(-1, 3)
        self.halves = np.broadcast_to(0.5 * np.asarray(box_sizes, dtype=float),
                                      (len(self.boxes),)).reshape(-1, 1)
        self.half = float(self.halves.max()) if len(self.boxes) else 0.0
        self._pt = cKDTree(self.points) if len(self.points) else None
        self._bt = cKDTree(self.boxes) if len(self.boxes) else None

    def of_path(self, path: np.ndarray, step: float) -> float:
        """Minimum distance (m) from the polyline ``path`` (K, 3) to the obstacles.

        ``step`` (m) is the sampling used to find candidates; the result is exact.
        """
        path = np.asarray(path, dtype=float)
        a_all, b_all = path[:-1], path[1:]
        if not len(a_all):
            return np.inf
        lens = np.array([np.linalg.norm(b - a) for a, b in zip(a_all, b_all, strict=True)])
        counts = np.maximum(2, np.ceil(lens / step).astype(np.int64) + 1)
        samples = [a + np.linspace(0, 1, n)[:, None] * (b - a)
                   for a, b, n in zip(a_all, b_all, counts, strict=True)]
        slacks = 0.5 * lens / (counts - 1)  # farthest segment point to a sample
        trees = [(tree, data, pad) for tree, data, pad in
                 ((self._pt, self.points, 0.0), (self._bt, self.boxes, self.half * np.sqrt(3)))
                 if tree is not None]
        if not trees:
            return np.inf
        # Any sample's nearest point or cube centre bounds the minimum from above, so a
        # candidate farther than that bound (+ slack + pad) from all of a segment's samples
        # cannot be the nearest obstacle: one bound prunes every segment at once.
        flat = np.concatenate(samples)
        bound = min(float(tree.query(flat)[0].min()) for tree, _, _ in trees)
        best = np.inf
        seg, cand = [], []  # cube candidates: their segment, their cube
        for tree, data, pad in trees:
            for i, s in enumerate(samples):
                reach = bound + slacks[i] + pad
                idx = np.unique(np.concatenate(
                    [np.asarray(j, dtype=np.int64) for j in tree.query_ball_point(s, reach)]
                ))
                if not len(idx):
                    continue
                if pad:
                    seg.append(np.full(len(idx), i))
                    cand.append(idx)
                else:
                    best = min(best, float(_segment_point_dist(a_all[i], b_all[i],
                                                               data[idx]).min()))
        if cand:  # one golden-section search for all segments' cubes
            i, idx = np.concatenate(seg), np.concatenate(cand)
            d = _segment_box_dist(a_all[i], b_all[i], self.boxes[idx], self.halves[idx])
            best = min(best, float(d.min()))
        return best
