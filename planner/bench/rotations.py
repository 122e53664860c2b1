"""Random rotations of a map for the paper's fairness rule.

The paper rotates its data "by uniformly random rotations" so that the comparison is not
biased by symmetries shared between the environment (walls on the axes) and one lattice.
The suite draws one sample of rotations per map and applies the same sample to every
lattice, neighbour set and method.

Quaternions are ``(w, x, y, z)`` with ``w >= 0``; matrices rotate column vectors.

Examples
--------
>>> q = sample_rotations("yaw", 3, seed=0)
>>> q.shape, bool(np.allclose(np.linalg.norm(q, axis=1), 1))
((3, 4), True)
>>> R = quaternion_matrix(q[0])
>>> bool(np.allclose(R @ R.T, np.eye(3))), bool(np.isclose(R[2, 2], 1.0))
(True, True)
>>> sample_rotations("none", 1)
array([[1., 0., 0., 0.]])
"""

from __future__ import annotations

import numpy as np

__all__ = ["ROTATION_KINDS", "sample_rotations", "quaternion_matrix", "rotate_about"]

ROTATION_KINDS = ("none", "yaw", "so3")


def sample_rotations(kind: str, k: int, seed: int = 0) -> np.ndarray:
    """``k`` rotations as unit quaternions, shape (k, 4).

    Parameters
    ----------
    kind : {"none", "yaw", "so3"}
        ``none``: the identity (k is then forced to 1). ``yaw``: uniform angle about the
        gravity axis z, for gravity-aligned maps (buildings, OctoMaps). ``so3``: uniform on
        the rotation group (Shoemake's subgroup algorithm), for aerial/unstructured use.
    k : int
        Number of rotations (>= 1).
    seed : int
        The same seed gives the same sample, for every lattice.
    """
    if kind not in ROTATION_KINDS:
        raise ValueError(f"rotation must be one of {', '.join(ROTATION_KINDS)}, got {kind!r}")
    if int(k) < 1:
        raise ValueError(f"rotations must be >= 1, got {k}")
    if kind == "none":
        return np.array([[1.0, 0.0, 0.0, 0.0]])
    rng = np.random.default_rng(seed)
    if kind == "yaw":
        a = rng.uniform(0.0, 2.0 * np.pi, size=int(k))
        q = np.stack([np.cos(a / 2), np.zeros_like(a), np.zeros_like(a), np.sin(a / 2)], 1)
    else:
        u1, u2, u3 = rng.uniform(0.0, 1.0, size=(3, int(k)))
        s1, s2 = np.sqrt(1.0 - u1), np.sqrt(u1)
        q = np.stack([s2 * np.cos(2 * np.pi * u3), s1 * np.sin(2 * np.pi * u2),
                      s1 * np.cos(2 * np.pi * u2), s2 * np.sin(2 * np.pi * u3)], 1)
    q[q[:, 0] < 0] *= -1.0
    return q


def quaternion_matrix(q) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def rotate_about(points, rotation: np.ndarray, centre) -> np.ndarray:
    """Points (N, 3) rotated by ``rotation`` (3, 3) about ``centre`` (3,), metres."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    c = np.asarray(centre, dtype=float)
    return (p - c) @ np.asarray(rotation, dtype=float).T + c
