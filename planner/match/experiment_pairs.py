"""Scan pairs of the Fig. 6 experiment, and the random draws every method shares.

Three kinds of pair:

* **truth** pairs, whose relative pose is known: scans simulated in geb079 at known poses
  (:mod:`planner.match.simulate`; each scan cast independently with its own range noise,
  so no point is shared: exact truth, the headline), the Velodyne sweeps with their
  ``relative.txt`` (itself a measurement: the report prints how far from it every method
  converges), or any user pair ``SOURCE REFERENCE TRANSFORM.txt``;
* the **consistency** pair, PCL's two room scans, which have no ground truth, only the
  odometry guess published with them (PCL's NDT tutorial: 0.6931 rad about z, then
  (1.79387, 0.720047, 0) m, room_scan2 into room_scan1's frame); each method matches A->B
  and B->A and the composition should be the identity. The guess is some 0.7 m from where
  every method converges, so the initial errors are drawn around a refined centre instead:
  the mean (translations averaged, rotations by ``Rotation.mean``) of one match from the
  guess on each named lattice, favouring none of them.

The fairness rule of the paper: trial ``k`` of a pair rotates both scans by one uniformly
random rotation (``scipy.spatial.transform.Rotation.random``), so that walls on the axes
favour no lattice, and starts from one random initial error (uniform direction, offset
uniform in [0, ``max_offset``] m, angle uniform in [0, ``max_angle``] degrees about a
uniform axis); both come from ``numpy.random.default_rng([seed, pair, k])``, so every
lattice and every anchor see the same draws, and trial ``k`` does not depend on how many
trials are run (``--trials`` can grow a resumed run).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from planner.errors import MapError, PlannerError
from planner.io import load_obstacles, load_points
from planner.lattice import NAMED_LATTICES
from planner.match.matcher import check_transform, match
from planner.match.simulate import BoxMap, lidar_directions, sample_pose_pairs

__all__ = ["Pair", "SOURCES", "Trial", "draw_trial", "geb079_pairs", "load_sources",
           "room_pair", "user_pair", "velodyne_pair"]

SOURCES = ("velodyne", "geb079", "room")
ROOM_GUESS = ((0.0, 0.0, 0.6931), (1.79387, 0.720047, 0.0))  # rotvec (rad), translation (m)
SEPARATIONS = (0.25, 0.5, 1.0)  # metres between the simulated scans of a pair


@dataclass
class Pair:
    """Two scans and what is known of the source -> reference transform.

    Attributes
    ----------
    name : str
        Label in tables and rows (unique within a run).
    source, reference : ndarray, shape (N, 3) and (M, 3)
        Metres, each in its own sensor frame.
    transform : ndarray, shape (4, 4)
        Source -> reference: the truth (``kind == "truth"``) or the guess the initial
        errors are drawn around (``kind == "consistency"``).
    kind : {"truth", "consistency"}
    group : str
        Source of the pair (``velodyne``, ``geb079``, ``room``, ``user``) for breakdowns.
    """

    name: str
    source: np.ndarray
    reference: np.ndarray
    transform: np.ndarray
    kind: str = "truth"
    group: str = "user"


@dataclass
class Trial:
    """One trial of a pair: the shared rotation and initial error (4x4 each)."""

    pair: int
    index: int
    rotation: np.ndarray
    error: np.ndarray

    @property
    def key(self) -> str:
        return f"{self.pair}/{self.index}"


def draw_trial(seed: int, pair: int, index: int, max_offset: float, max_angle: float
               ) -> Trial:
    """The rotation of the pair and the initial error of trial ``index`` (see module)."""
    rng = np.random.default_rng([seed, pair, index])
    rot = np.eye(4)
    rot[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    axis = Rotation.random(random_state=rng).apply([1.0, 0.0, 0.0])
    err = np.eye(4)
    err[:3, :3] = Rotation.from_rotvec(axis * np.radians(rng.uniform(0, max_angle))
                                       ).as_matrix()
    d = rng.normal(size=3)
    err[:3, 3] = d / np.linalg.norm(d) * rng.uniform(0, max_offset)
    return Trial(pair, index, rot, err)


def _points(path: Path) -> np.ndarray:
    return load_points(path)


def _transform_file(path: Path) -> np.ndarray:
    try:
        m = np.loadtxt(path, dtype=float)
    except (OSError, ValueError) as exc:
        raise PlannerError(f"{path}: not a 4x4 transform ({' '.join(str(exc).split())})"
                           ) from None
    return check_transform(m, str(path), atol=1e-4)  # text files round their digits


def user_pair(source: str | Path, reference: str | Path, transform: str | Path) -> Pair:
    """A pair from files: two point files and the source -> reference 4x4 (text)."""
    s, r, t = Path(source), Path(reference), Path(transform)
    return Pair(f"{s.stem}->{r.stem}", _points(s), _points(r), _transform_file(t))


def velodyne_pair(data: Path) -> Pair:
    """The Velodyne sweeps: 251371071 (source) into 251370668's frame, ``relative.txt``."""
    d = data / "velodyne"
    return Pair("velodyne", _points(d / "251371071.pcd"), _points(d / "251370668.pcd"),
                _transform_file(d / "relative.txt"), group="velodyne")


def geb079_pairs(data: Path, per_separation: int = 1, seed: int = 0, noise: float = 0.02,
                 azimuth_step: float = 0.2) -> list[Pair]:
    """Scans simulated in geb079 at known poses, ``per_separation`` pairs per separation
    (:data:`SEPARATIONS`), range noise ``noise`` (m, standard deviation)."""
    box_map = BoxMap(load_obstacles(data / "octomap" / "geb079.bt"))
    rng = np.random.default_rng([seed, 79])
    dirs = lidar_directions(azimuth_step)
    out = []
    for i, (sep, a, b) in enumerate(sample_pose_pairs(box_map, SEPARATIONS, per_separation,
                                                      rng)):
        ref, src = box_map.scan(a, dirs, noise, rng), box_map.scan(b, dirs, noise, rng)
        out.append(Pair(f"geb079 {sep:g} m #{i % per_separation + 1}", src, ref,
                        np.linalg.solve(a, b), group="geb079"))
    return out


def room_pair(data: Path, cell_volume: float = 0.001, levels: int = 4) -> Pair:
    """PCL's room scans: room_scan2 (source) into room_scan1's frame, around the published
    odometry guess refined by every named lattice (see the module)."""
    d = data / "pcl_room"
    src, ref = _points(d / "room_scan2.pcd"), _points(d / "room_scan1.pcd")
    guess = np.eye(4)
    guess[:3, :3] = Rotation.from_rotvec(ROOM_GUESS[0]).as_matrix()
    guess[:3, 3] = ROOM_GUESS[1]
    est = [match(src, ref, lattice=n, cell_volume=cell_volume, levels=levels, init=guess
                 ).transform for n in NAMED_LATTICES]
    centre = np.eye(4)
    centre[:3, :3] = Rotation.from_matrix([m[:3, :3] for m in est]).mean().as_matrix()
    centre[:3, 3] = np.mean([m[:3, 3] for m in est], axis=0)
    return Pair("room", src, ref, centre, kind="consistency", group="room")


def load_sources(names: list[str], data: str | Path, *, seed: int = 0,
                 simulated_per_separation: int = 1, cell_volume: float = 0.001,
                 levels: int = 4) -> list[Pair]:
    """The pairs of the named sources (:data:`SOURCES`) from the data folder ``data``.

    Raises
    ------
    PlannerError
        An unknown source name, or a data file that is missing (one line naming it).
    """
    root = Path(data)
    unknown = [n for n in names if n not in SOURCES]
    if unknown:
        raise PlannerError(f"unknown source {unknown[0]!r}: choose from {', '.join(SOURCES)}")
    need = {"velodyne": "velodyne/relative.txt", "geb079": "octomap/geb079.bt",
            "room": "pcl_room/room_scan1.pcd"}
    for n in names:
        if not (root / need[n]).is_file():
            raise MapError(f"{root / need[n]}: not found (source {n!r}; --data names the "
                           f"data folder)")
    out: list[Pair] = []
    for n in names:
        if n == "velodyne":
            out.append(velodyne_pair(root))
        elif n == "geb079":
            out += geb079_pairs(root, simulated_per_separation, seed)
        else:
            out.append(room_pair(root, cell_volume, levels))
    return out
