"""The registration anchors of the scan-matching experiment, from small_gicp (Koide,
"small_gicp: Efficient and parallel algorithms for point cloud registration", JOSS 2024), in
the optional ``match`` extra (``pip install 'lattice-planner[match]'``).

Each anchor is stated as configured (:data:`ANCHORS`); all run on one thread (the lattice
matcher is single-threaded too) from the same initial guess as the lattice matcher, and
their time includes their preprocessing (voxel downsampling, covariance or normal
estimation, k-d trees of both clouds):

* ``gicp``: ``small_gicp.align`` with its defaults, i.e. GICP (generalized ICP,
  plane-to-plane), 0.25 m voxel downsampling, 1 m maximum correspondence distance, at most
  20 iterations;
* ``gicp-c2f``: GICP coarse to fine, three stages at 0.4, 0.2 and 0.1 m downsampling with
  maximum correspondence distances of 1.0, 0.5 and 0.25 m (2.5 voxels), 20 iterations
  each, each stage starting from the previous one's result;
* ``plane-icp``: the point-to-plane ICP of the library (``registration_type="PLANE_ICP"``)
  with otherwise the defaults of ``gicp``: the classic ICP baseline, kept as a weaker row.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from planner.errors import PlannerError

__all__ = ["ANCHORS", "EXTRA_MESSAGE", "Stage", "available", "register"]

EXTRA_MESSAGE = ("the registration anchors need the 'match' extra: "
                 "pip install 'lattice-planner[match]'")


class Stage(NamedTuple):
    """One registration stage: small_gicp's type, downsampling voxel (m), maximum
    correspondence distance (m)."""

    kind: str
    downsampling: float
    max_distance: float


ANCHORS: dict[str, tuple[Stage, ...]] = {
    "gicp": (Stage("GICP", 0.25, 1.0),),
    "gicp-c2f": (Stage("GICP", 0.4, 1.0), Stage("GICP", 0.2, 0.5), Stage("GICP", 0.1, 0.25)),
    "plane-icp": (Stage("PLANE_ICP", 0.25, 1.0),),
}


def available() -> bool:
    """Whether small_gicp can be imported."""
    try:
        import small_gicp  # noqa: F401
    except ImportError:
        return False
    return True


def register(name: str, source: np.ndarray, reference: np.ndarray,
             init: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Register ``source`` ((N, 3), m) onto ``reference`` ((M, 3), m) with the anchor
    ``name`` (a key of :data:`ANCHORS`) from ``init`` (4x4, source -> reference).

    Returns
    -------
    transform : ndarray, shape (4, 4)
        Source -> reference.
    seconds : float
        CPU time of the calling process, preprocessing of both clouds included.

    Raises
    ------
    PlannerError
        An unknown anchor, or the ``match`` extra not installed (one line naming it).
    """
    if name not in ANCHORS:
        raise PlannerError(f"unknown anchor {name!r}: choose from {', '.join(ANCHORS)}")
    try:
        import small_gicp
    except ImportError:
        raise PlannerError(EXTRA_MESSAGE) from None
    m = np.eye(4) if init is None else np.asarray(init, dtype=float)
    ref = np.asarray(reference, dtype=float)
    src = np.asarray(source, dtype=float)
    t0 = time.process_time()
    for st in ANCHORS[name]:
        # Normals and covariances from the 10 nearest neighbours: the library's default.
        target, tree = small_gicp.preprocess_points(ref, st.downsampling, num_threads=1)
        moved, _ = small_gicp.preprocess_points(src, st.downsampling, num_threads=1)
        res = small_gicp.align(target, moved, tree, m, registration_type=st.kind,
                               max_correspondence_distance=st.max_distance, num_threads=1)
        m = np.array(res.T_target_source)
    return m, time.process_time() - t0
