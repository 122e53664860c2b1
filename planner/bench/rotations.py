"""Random rotations of a map for the paper's fairness rule.

The paper rotates its data "by uniformly random rotations" so that the comparison is not
biased by symmetries shared between the environment (walls on the axes) and one lattice.
The suite draws one sample of rotations per map and applies the same sample to every
lattice, neighbour set and method.

Quaternions are ``(x, y, z, w)`` (the order of ROS and :class:`scipy.spatial.transform.Rotation`)
with ``w >= 0``; rows and files name the order (``quaternion_xyzw``); matrices rotate column
vectors.

Examples
--------
>>> q = sample_rotations("yaw", 3, seed=0)
>>> q.shape, bool(np.allclose(np.linalg.norm(q, axis=1), 1))
((3, 4), True)
>>> R = Rotation.from_quat(q[0]).as_matrix()
>>> bool(np.allclose(R @ R.T, np.eye(3))), bool(np.isclose(R[2, 2], 1.0))
(True, True)
>>> sample_rotations("none", 1)
array([[0., 0., 0., 1.]])
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["IDENTITY_XYZW", "ROTATION_KINDS", "sample_rotations", "rotate_about"]

IDENTITY_XYZW = (0.0, 0.0, 0.0, 1.0)

ROTATION_KINDS = ("none", "yaw", "so3")


def sample_rotations(kind: str, k: int, seed: int = 0) -> np.ndarray:
    """``k`` rotations as unit quaternions ``(x, y, z, w)``, shape (k, 4), ``w >= 0``.

    Parameters
    ----------
    kind : {"none", "yaw", "so3"}
        ``none``: the identity (k is then forced to 1). ``yaw``: uniform angle about the
        gravity axis z, for gravity-aligned maps (buildings, OctoMaps). ``so3``: uniform on
        the rotation group (``scipy.spatial.transform.Rotation.random``), for aerial or
        unstructured use.
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
        return np.array([IDENTITY_XYZW])
    rng = np.random.default_rng(seed)
    if kind == "yaw":
        rot = Rotation.from_euler("z", rng.uniform(0.0, 2.0 * np.pi, size=(int(k), 1)))
    else:
        rot = Rotation.random(int(k), random_state=rng)
    q = rot.as_quat()
    q[q[:, 3] < 0] *= -1.0  # one of the two equal quaternions: w >= 0
    return q


def rotate_about(points, rotation: np.ndarray, centre) -> np.ndarray:
    """Points (N, 3) rotated by ``rotation`` (3, 3) about ``centre`` (3,), metres."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    c = np.asarray(centre, dtype=float)
    return (p - c) @ np.asarray(rotation, dtype=float).T + c
