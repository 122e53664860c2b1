"""Coarse-to-fine rigid 6-DOF scan matching on multi-resolution lattice voxel lists.

After Ryde and Hu (3D mapping with multi-resolution occupied voxel lists): the reference
scan (or map) is held as a :class:`~planner.match.multires.MultiResVoxelList`; the
objective at a level is the number of source points whose lattice cell, after the
candidate transform, is occupied in the reference's list at that level. The pose is
searched locally at each level by a discrete neighbourhood (pattern) search over the six
degrees of freedom: +-step along x, y, z and +-angle about x, y, z (rotations about the
transformed source's centroid), moving to the best strict improvement and halving the
steps when none improves. The translation step starts at half the level's cell side and the
rotation step is that step over the source's RMS radius, so both move points by about half
a cell; a level ends when the step falls below an eighth of its cell side (the finest
level: a sixteenth), and the search continues at the next finer level. With the
refinement (the default) the search ends at the refinement's plane level (level 1, cells
of twice the finest side): the refinement places the pose more finely than the finest
level's discrete steps could, and the finest level's search was a match's costliest part.

At each level the source is summarised by the means of its points per cell of that level's
lattice scaled by one half, each weighted by its point count, so the weighted score
approximates the point count at a fraction of the cost; the reported score is counted on
every source point at the finest level. The discrete pose is then refined continuously
(:mod:`planner.match.refine`: point-to-plane least squares on the matched cells' planes),
and the refined pose is kept unless it holds fewer than 95% of the discrete pose's points
in occupied cells. Rotations are :class:`scipy.spatial.transform.
Rotation`; transforms are 4x4 homogeneous matrices (metres) taking source coordinates into
the reference frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from planner.errors import MapError, PlannerError
from planner.lattice import Lattice, cosets
from planner.match.multires import MultiResVoxelList, resolve_lattice
from planner.match.refine import refine as refine_pose
from planner.occupancy.keys import pack

__all__ = ["MatchResult", "match", "pose_matrix", "pose_error", "check_transform"]

_MAX_MOVES = 60  # moves per level before the step is forced down (a bound, rarely hit)


@dataclass
class MatchResult:
    """Outcome of :func:`match`.

    Attributes
    ----------
    transform : ndarray, shape (4, 4)
        Source -> reference rigid transform (metres).
    score : int
        Source points whose finest-level cell is occupied in the reference.
    fraction : float
        ``score`` over the number of source points.
    levels : int
        Resolutions searched.
    iterations : list of int
        Accepted moves per level searched, coarsest first (with the refinement, the search
        ends at the refinement's plane level, :attr:`MultiResVoxelList.plane_level`).
    evaluations : int
        Candidate poses scored.
    refinement : int
        Gauss-Newton steps of the final refinement kept (0: none, or not kept).
    seconds : float
        Wall time of the match (building the reference excluded when it was given built).
    """

    transform: np.ndarray
    score: int
    fraction: float
    levels: int
    iterations: list[int] = field(default_factory=list)
    evaluations: int = 0
    seconds: float = 0.0
    refinement: int = 0

    def as_dict(self) -> dict:
        """JSON-ready: ``transform`` row-major 4x4, quaternion ``x, y, z, w``."""
        q = Rotation.from_matrix(self.transform[:3, :3]).as_quat()
        return {"transform": self.transform.tolist(), "translation": self.transform[:3, 3]
                .tolist(), "quaternion_xyzw": q.tolist(), "score": self.score,
                "fraction": self.fraction, "levels": self.levels,
                "iterations": self.iterations, "evaluations": self.evaluations,
                "refinement": self.refinement, "seconds": self.seconds}


def pose_matrix(xyz_rpy) -> np.ndarray:
    """4x4 transform from ``x, y, z`` (m) and ``roll, pitch, yaw`` (degrees, extrinsic
    x-y-z)."""
    v = np.asarray(xyz_rpy, dtype=float)
    if v.shape != (6,) or not np.isfinite(v).all():
        raise PlannerError(f"a pose needs six finite numbers x,y,z,roll,pitch,yaw, got {v}")
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("xyz", v[3:], degrees=True).as_matrix()
    m[:3, 3] = v[:3]
    return m


def pose_error(estimate: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(position error m, rotation error degrees) of ``truth^-1 @ estimate``."""
    d = np.linalg.solve(truth, estimate)
    ang = float(np.degrees(Rotation.from_matrix(d[:3, :3]).magnitude()))
    return float(np.linalg.norm(d[:3, 3])), ang


def check_transform(m, what: str, atol: float = 1e-6) -> np.ndarray:
    """``m`` as a (4, 4) float rigid transform; :class:`PlannerError` naming ``what`` if it
    is not finite, not 4x4, or its rotation block is not orthonormal within ``atol``."""
    t = np.asarray(m, dtype=float)
    if t.shape != (4, 4) or not np.isfinite(t).all():
        raise PlannerError(f"{what}: expected a finite 4x4 matrix, got shape {t.shape}")
    r = t[:3, :3]
    if not np.allclose(r @ r.T, np.eye(3), atol=atol) or np.linalg.det(r) < 0:
        raise PlannerError(f"{what}: not a rigid transform (rotation block not orthonormal)")
    return t


def _as_cloud(points, what: str) -> np.ndarray:
    try:
        x = np.ascontiguousarray(np.asarray(points, dtype=float))
    except (TypeError, ValueError):
        raise MapError(f"{what} must be a numeric (N, 3) array") from None
    if x.ndim != 2 or x.shape[1] != 3:
        raise MapError(f"{what} must have shape (N, 3), got {x.shape}")
    if len(x) < 3:
        raise MapError(f"{what} needs at least 3 points, got {len(x)}")
    if not np.isfinite(x).all():
        raise MapError(f"{what} contains NaN or infinite coordinates")
    return x


def _summary(points: np.ndarray, lattice: Lattice) -> tuple[np.ndarray, np.ndarray]:
    """Per-cell means of ``points`` and their counts, cells of ``lattice``."""
    _, inv, counts = np.unique(pack(cosets.quantize(lattice, points)), return_inverse=True,
                               return_counts=True)
    means = np.stack([np.bincount(inv, points[:, j], len(counts)) for j in range(3)], axis=1)
    return np.ascontiguousarray(means / counts[:, None]), counts.astype(float)


class _Scorer:
    """Scores batches of poses of a (summarised) source against one reference level."""

    def __init__(self, pts: np.ndarray, wts: np.ndarray, level) -> None:
        self.pts, self.wts, self.lv = pts, wts, level
        self.evaluations = 0

    def __call__(self, rots: np.ndarray, trans: np.ndarray) -> np.ndarray:
        out = self.lv.score(self.pts, self.wts, np.ascontiguousarray(rots),
                            np.ascontiguousarray(trans))
        self.evaluations += len(rots)
        return out


def _neighbours(r: np.ndarray, t: np.ndarray, c_src: np.ndarray, dt: float, dr: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """The 12 neighbouring poses: +-dt along each axis, +-dr (rad) about each axis through
    the transformed source centroid."""
    rots = np.repeat(r[None], 12, axis=0)
    trans = np.repeat(t[None], 12, axis=0)
    eye = np.eye(3)
    trans[:6] += np.concatenate([eye, -eye]) * dt
    c = r @ c_src + t
    turns = Rotation.from_rotvec(np.concatenate([eye, -eye]) * dr).as_matrix()
    rots[6:] = turns @ r
    trans[6:] = (turns @ (t - c)) + c
    return rots, trans


def _search(score: _Scorer, r, t, c_src, dt, dr, dt_stop) -> tuple:
    cur = score(r[None], t[None])[0]
    moves = 0
    while dt >= dt_stop:
        rots, trans = _neighbours(r, t, c_src, dt, dr)
        s = score(rots, trans)
        best = int(np.argmax(s))
        if s[best] > cur and moves < _MAX_MOVES:
            r, t, cur = rots[best], trans[best], s[best]
            moves += 1
        else:
            dt, dr = dt / 2, dr / 2
    return r, t, moves


def match(source, reference, *, lattice: str | Lattice = "fcc", cell_volume: float = 0.001,
          levels: int = 4, init=None, scale: float = 2.0, summary: float = 2.0,
          refine: bool = True) -> MatchResult:
    """Estimate the rigid transform taking ``source`` into ``reference``'s frame.

    Parameters
    ----------
    source : array_like, shape (N, 3)
        Source scan, metres.
    reference : array_like, shape (M, 3), or MultiResVoxelList
        Reference scan or map (metres); a built :class:`MultiResVoxelList` is used as is
        (then ``lattice``, ``cell_volume``, ``levels`` and ``scale`` come from it).
    lattice : str or Lattice
        ``cubic``, ``bcc``, ``fcc``, ``mcc``, ``hex`` or any 3D :class:`Lattice` (the
        finest level; its own cell volume).
    cell_volume : float
        Finest cell volume (m^3) for a named lattice.
    levels : int
        Resolutions; the coarsest cell side is ``cell_volume**(1/3) * scale**(levels-1)``
        and should be comparable to the initial error.
    init : array_like, shape (4, 4), optional
        Initial source -> reference transform (identity by default).
    scale : float
        Generator scale between levels.
    summary : float
        The source is summarised per cell of each level's generator divided by this
        (per-cell means weighted by counts; 2: cells of half the side).
    refine : bool
        Refine the discrete pose continuously (see the module).

    Returns
    -------
    MatchResult

    Raises
    ------
    MapError, LatticeError, PlannerError
        Bad clouds, lattice, levels or initial transform.
    """
    src = _as_cloud(source, "source")
    if isinstance(reference, MultiResVoxelList):
        ref = reference
    else:
        ref = MultiResVoxelList(_as_cloud(reference, "reference"),
                                resolve_lattice(lattice, cell_volume), levels, scale)
    m0 = np.eye(4) if init is None else check_transform(init, "init")
    t0 = time.perf_counter()
    r, t = m0[:3, :3].copy(), m0[:3, 3].copy()
    c_src = src.mean(axis=0)
    radius = max(float(np.sqrt(((src - c_src) ** 2).sum(axis=1).mean())), 1e-9)
    iterations, evaluations = [], 0
    last = ref.plane_level if refine else 0
    for k in range(ref.levels - 1, last - 1, -1):
        lv = ref.level(k)
        pts, wts = _summary(src, Lattice(lv.lattice.generator / summary))
        score = _Scorer(pts, wts, lv)
        dt = lv.side / 2
        stop = lv.side / (16 if k == 0 else 8)
        r, t, moves = _search(score, r, t, c_src, dt, dt / radius, stop)
        iterations.append(moves)
        evaluations += score.evaluations
    fine = _Scorer(src, np.ones(len(src)), ref.level(0))
    n_hit = int(round(fine(r[None], t[None])[0]))
    steps = 0
    if refine:
        # The source summarised as for the plane level's search: points of the same
        # half-cell fall on the same plane anyway.
        plane_lat = ref.level(ref.plane_level).lattice
        pts, wts = _summary(src, Lattice(plane_lat.generator / summary))
        r2, t2, steps = refine_pose(pts, wts, ref.planes(), plane_lat, r, t, 20)
        n2 = int(round(fine(r2[None], t2[None])[0]))
        if steps and n2 >= 0.95 * n_hit:
            r, t, n_hit = r2, t2, n2
        else:
            steps = 0
    final = np.eye(4)
    final[:3, :3], final[:3, 3] = r, t
    seconds = time.perf_counter() - t0
    return MatchResult(final, n_hit, n_hit / len(src), ref.levels, iterations,
                       evaluations + 1 + (1 if refine else 0), seconds, steps)
