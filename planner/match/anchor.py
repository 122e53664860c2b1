"""The ICP anchor of the Fig. 6 table: small_gicp's point-to-plane ICP (Koide,
"small_gicp: Efficient and parallel algorithms for point cloud registration", JOSS 2024),
in the optional ``match`` extra (``pip install 'lattice-planner[match]'``).

Run with its library defaults except one thread (the matcher is single-threaded too):
0.25 m voxel downsampling, 1 m maximum correspondence distance, at most 20 iterations.
Point-to-plane rather than GICP: the classic ICP baseline of the registration literature.
"""

from __future__ import annotations

import time

import numpy as np

from planner.errors import PlannerError

__all__ = ["EXTRA_MESSAGE", "available", "icp"]

EXTRA_MESSAGE = "the ICP anchor needs the 'match' extra: pip install 'lattice-planner[match]'"


def available() -> bool:
    """Whether small_gicp can be imported."""
    try:
        import small_gicp  # noqa: F401
    except ImportError:
        return False
    return True


def icp(source: np.ndarray, reference: np.ndarray, init: np.ndarray | None = None,
        downsampling: float = 0.25, max_distance: float = 1.0) -> tuple[np.ndarray, float]:
    """Point-to-plane ICP of ``source`` ((N, 3), m) onto ``reference`` ((M, 3), m).

    Returns
    -------
    transform : ndarray, shape (4, 4)
        Source -> reference.
    seconds : float
        Wall time, preprocessing (downsampling, normals, k-d tree) included.

    Raises
    ------
    PlannerError
        When the ``match`` extra is not installed (one line naming it).
    """
    try:
        import small_gicp
    except ImportError:
        raise PlannerError(EXTRA_MESSAGE) from None
    m0 = np.eye(4) if init is None else np.asarray(init, dtype=float)
    t0 = time.perf_counter()
    res = small_gicp.align(np.asarray(reference, dtype=float), np.asarray(source, dtype=float),
                           m0, registration_type="PLANE_ICP",
                           downsampling_resolution=downsampling,
                           max_correspondence_distance=max_distance, num_threads=1)
    return np.array(res.T_target_source), time.perf_counter() - t0
