"""The result types of the readers: :class:`Obstacles` (what a map says) and :class:`Scenarios`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.errors import MapError

UNKNOWN_POLICIES = ("blocked", "free")


@dataclass(frozen=True, eq=False)  # eq=False: element-wise array equality is not a bool
class Obstacles:
    """Everything a map file says about space: occupied, observed free, and (implicitly) unknown.

    Space is tri-state.  *Occupied* space is the union of the points (each a tiny obstacle)
    and the solid boxes.  *Free* space is what the file says was observed empty: the free
    boxes, and, when ``origins`` is set, every ray from a point's sensor origin to the point
    (its end excluded).  Everything else is *unknown*; ``unknown_default`` says how a planner
    should treat it unless the user decides otherwise.

    Attributes
    ----------
    points : ndarray, shape (N, d), float64
        Sensed obstacle points, metres (``d`` = :attr:`dim`).  May be empty.
    boxes : ndarray, shape (M, d), float64
        Centres of solid axis-aligned cubes (squares in 2D), metres.  May be empty.
    box_size : float
        The edge of every box when they all have one size; when sizes differ (an OctoMap with
        pruned leaves), the largest one, so code that uses a single size stays conservative.
        0.0 when there are no boxes.  Per-box edges are in ``box_sizes``.
    bounds : ndarray, shape (2, d), or None
        ``[min, max]`` corners of the map's world box, metres, or None when the format has no
        intrinsic bounds (point clouds, OctoMap).
    resolution : float or None
        Native cell size, metres (OctoMap ``res``, 1.0 for ``.3dmap``, the ROS map's
        ``resolution``); None for raw clouds.
    source : str
        File name the obstacles came from (``"<array>"`` for in-memory data).
    box_sizes : ndarray, shape (M,), float64
        Edge of each box, metres.  Default: ``box_size`` for every box.
    free_boxes : ndarray, shape (K, d), float64
        Centres of axis-aligned cubes observed free (OctoMap free leaves, ROS map free cells).
    free_box_sizes : ndarray, shape (K,), float64
        Edge of each free box, metres.
    origins : ndarray, shape (S, d), float64, or None
        Sensor origins (one per scan), metres, for ray-cast free space; None when unknown.
    point_origin : ndarray, shape (N,), int64, or None
        Index into ``origins`` of each point's scan; set exactly when ``origins`` is.
    unknown_default : str
        ``"blocked"`` when the file carries free-space information (free boxes or sensor
        origins), else ``"free"`` (a plain cloud: everything not occupied counts as free).
    dropped_nonfinite : int
        Points dropped because a coordinate was NaN or infinite (organized clouds mark
        missing returns this way).
    dim : int
        2 for 2D maps (ROS map_server), else 3.
    frame : str or None
        The coordinate frame the points are in when the file names one (a bag's fixed
        frame); None otherwise.
    read : dict or None
        What the reader chose when the file holds more than it read (a bag: ``topic``,
        ``topic_given``, ``topics``, ``fixed_frame``, ``fixed_frame_given``, ``max_clouds``,
        ``clouds``, ``clouds_in_topic``), for path files and reports; None otherwise.
    """

    points: np.ndarray
    boxes: np.ndarray
    box_size: float
    bounds: np.ndarray | None
    resolution: float | None
    source: str
    box_sizes: np.ndarray | None = None
    free_boxes: np.ndarray | None = None
    free_box_sizes: np.ndarray | None = None
    origins: np.ndarray | None = None
    point_origin: np.ndarray | None = None
    unknown_default: str | None = None
    dropped_nonfinite: int = 0
    dim: int = 3
    frame: str | None = None
    read: dict | None = None

    def __post_init__(self) -> None:
        # Coerce once here so every consumer can rely on float64 (N, d) arrays.
        d = self.dim
        if d not in (2, 3):
            raise MapError(f"{self.source}: Obstacles.dim must be 2 or 3, got {d}")
        for name in ("points", "boxes", "free_boxes"):
            self._set(name, self._rows(name, getattr(self, name)))
        self._set("box_sizes", self._sizes("box_sizes", self.box_sizes, len(self.boxes),
                                           self.box_size))
        self._set("free_box_sizes", self._sizes("free_box_sizes", self.free_box_sizes,
                                                len(self.free_boxes), 0.0))
        self._set("box_size", float(self.box_sizes.max()) if len(self.boxes) else
                  float(self.box_size))
        if self.bounds is not None:
            b = np.asarray(self.bounds, dtype=np.float64)
            if b.shape != (2, d):
                raise MapError(f"{self.source}: Obstacles.bounds must have shape (2, {d}), "
                               f"got {b.shape}")
            self._set("bounds", b)
        if (self.origins is None) != (self.point_origin is None):
            raise MapError(f"{self.source}: Obstacles.origins and point_origin go together")
        if self.origins is not None:
            self._set("origins", self._rows("origins", self.origins))
            idx = np.asarray(self.point_origin, dtype=np.int64).reshape(-1)
            if len(idx) != len(self.points) or (
                    len(idx) and (idx.min() < 0 or idx.max() >= len(self.origins))):
                raise MapError(f"{self.source}: Obstacles.point_origin must index origins, "
                               f"one entry per point")
            self._set("point_origin", idx)
        policy = self.unknown_default
        if policy is None:
            policy = "blocked" if self.has_free_space else "free"
        if policy not in UNKNOWN_POLICIES:
            raise MapError(f"{self.source}: unknown_default must be 'blocked' or 'free', "
                           f"got {policy!r}")
        self._set("unknown_default", policy)
        self._set("dropped_nonfinite", int(self.dropped_nonfinite))

    # -- derived views ------------------------------------------------------------------------
    @property
    def has_free_space(self) -> bool:
        """True when the file says which space was observed free (free boxes or origins)."""
        return len(self.free_boxes) > 0 or self.origins is not None

    def rotated(self, rotation, centre) -> tuple[Obstacles, np.ndarray]:
        """The map turned rigidly by ``rotation`` about ``centre`` (the benchmark's fairness rule).

        Points, sensor origins and box centres (occupied and free) are rotated.  The boxes
        themselves become *oriented* solids, which this type cannot store: their edges stay
        in ``box_sizes`` / ``free_box_sizes`` and the caller must treat box k as
        ``{R @ x + t : |x - boxes_unrotated[k]| <= size / 2}``, e.g. with
        ``exact_box_inflation(lo, hi, lattice, radius, rotation=R, translation=t)``.
        ``bounds`` becomes None (an axis-aligned box no longer describes the map).

        Parameters
        ----------
        rotation : array_like, shape (d, d)
            Proper rotation matrix R.
        centre : array_like, shape (d,)
            Fixed point of the rotation, metres.

        Returns
        -------
        obstacles : Obstacles
            The rotated map (``source`` unchanged).
        translation : ndarray, shape (d,)
            ``t = c - R c``: the map's rigid motion is ``x -> R x + t``.
        """
        R = np.asarray(rotation, dtype=np.float64)
        c = np.asarray(centre, dtype=np.float64).reshape(-1)
        d = self.dim
        if R.shape != (d, d) or not np.allclose(R @ R.T, np.eye(d), atol=1e-9) \
                or np.linalg.det(R) <= 0 or c.shape != (d,):
            raise MapError(f"{self.source}: rotated() needs a proper ({d}, {d}) rotation and "
                           f"a ({d},) centre")
        t = c - R @ c

        def move(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a @ R.T + t

        from dataclasses import replace

        return replace(self, points=move(self.points), boxes=move(self.boxes),
                       free_boxes=move(self.free_boxes), origins=move(self.origins),
                       bounds=None, unknown_default=self.unknown_default), t

    def box_centre_points(self) -> np.ndarray:
        """Occupied boxes as points: each box filled with a grid of cubes of edge
        ``resolution`` (else the smallest box edge): an OctoMap leaf of 2^k voxels per side
        gives its (2^k)^d finest-voxel centres.

        Returns
        -------
        ndarray, shape (P, d), float64
            Metres; ``boxes`` itself when every box has the same size.
        """
        return fill_boxes(self.boxes, self.box_sizes, self.resolution)

    def robust_bounds(self) -> tuple[np.ndarray, int]:
        """Bounding box of the occupied geometry without far outliers.

        Returns
        -------
        bounds : ndarray, shape (2, d)
            ``[min, max]`` of points and boxes (box extents included) once outliers are set
            aside, metres.
        n_outliers : int
            Points left out (see :func:`planner.io.robust_extent`).
        """
        half = self.box_sizes[:, None] / 2
        parts = [self.points, self.boxes - half, self.boxes + half]
        allp = np.concatenate([p for p in parts if len(p)] or [np.zeros((0, self.dim))])
        if not len(allp):
            raise MapError(f"{self.source}: no obstacles to take bounds of")
        return robust_extent(allp)

    # -- helpers ------------------------------------------------------------------------------
    def _set(self, name: str, value) -> None:
        object.__setattr__(self, name, value)

    def _rows(self, name: str, value) -> np.ndarray:
        arr = np.asarray(value if value is not None else (), dtype=np.float64)
        if arr.size == 0:
            arr = arr.reshape(0, self.dim)
        if arr.ndim != 2 or arr.shape[1] != self.dim:
            raise MapError(f"{self.source}: Obstacles.{name} must have shape (N, {self.dim}), "
                           f"got {arr.shape}")
        return np.ascontiguousarray(arr)

    def _sizes(self, name: str, value, n: int, default: float) -> np.ndarray:
        if value is None:
            value = np.broadcast_to(np.asarray(default, dtype=np.float64), (n,))
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
        if arr.shape != (n,):
            raise MapError(f"{self.source}: Obstacles.{name} must have one entry per box "
                           f"({n}), got {arr.shape}")
        if n and not (np.isfinite(arr).all() and (arr >= 0).all()):
            raise MapError(f"{self.source}: Obstacles.{name} must be finite and >= 0")
        return np.array(arr)


@dataclass(frozen=True, eq=False)
class Scenarios:
    """MovingAI ``.3dscen`` start/goal queries.

    Attributes
    ----------
    starts, goals : ndarray, shape (K, 3), int64
        Voxel coordinates (0-based; voxel (x, y, z) is the unit cube centred on that point).
    costs : ndarray, shape (K,), float64
        Optimal path cost (26-neighbour cubic lattice, no corner cutting), voxel units.
    heuristic_ratios : ndarray, shape (K,), float64
        Optimal cost divided by the octile heuristic, as listed in the file.
    map_name : str
        Map file named on the second line.
    source : str
        Scenario file name.
    """

    starts: np.ndarray
    goals: np.ndarray
    costs: np.ndarray
    heuristic_ratios: np.ndarray
    map_name: str
    source: str

    def __len__(self) -> int:
        return len(self.costs)


# -- geometry over validated points ---------------------------------------------------------
# A filled box set larger than this is refused (a corrupt coarse OctoMap leaf would otherwise
# expand to billions of points); no real map comes near it.
MAX_FILLED_POINTS = 100_000_000


def fill_boxes(centres: np.ndarray, sizes: np.ndarray, step: float | None = None) -> np.ndarray:
    """Fill each box with a grid of cubes of edge ``step``; return their centres.

    Parameters
    ----------
    centres : ndarray, shape (M, d)
        Box centres, metres.
    sizes : ndarray, shape (M,)
        Box edges, metres; each a whole multiple of ``step`` (as in an OctoMap).
    step : float, optional
        Edge of the filling cubes, metres; default the smallest box edge.

    Returns
    -------
    ndarray, shape (P, d), float64
    """
    if not len(centres):
        return centres.copy()
    step = float(sizes.min()) if step is None else float(step)
    if step <= 0 or np.all(sizes == step):
        return centres.copy()
    per = np.rint(sizes / step).astype(np.int64)
    d = centres.shape[1]
    total = int((per.astype(np.float64) ** d).sum())
    if total > MAX_FILLED_POINTS:
        raise MapError(f"boxes fill {total} cubes of {step:g} m (limit {MAX_FILLED_POINTS})")
    out = []
    for n in np.unique(per):
        sel = centres[per == n]
        ticks = (np.arange(n) - (n - 1) / 2) * step
        grid = np.stack(np.meshgrid(*([ticks] * d), indexing="ij"), axis=-1).reshape(-1, d)
        out.append((sel[:, None, :] + grid[None]).reshape(-1, d))
    return np.concatenate(out)


def robust_extent(points: np.ndarray, tail: float = 1e-3) -> tuple[np.ndarray, int]:
    """Bounding box of ``points`` that one far outlier cannot blow up.

    The core box spans the ``tail`` and ``1 - tail`` quantiles per axis.  A point is an outlier
    when it lies more than one core width (at least 1 m) beyond the core on some axis; the
    result is the exact bounding box of the other points.

    Parameters
    ----------
    points : ndarray, shape (N, d)
        Finite coordinates, metres, N >= 1.
    tail : float
        Quantile left out on each side when sizing the core.

    Returns
    -------
    bounds : ndarray, shape (2, d)
        ``[min, max]`` of the non-outliers, metres.
    n_outliers : int
        Points outside it.

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.vstack([np.random.default_rng(0).uniform(0, 10, (1000, 3)), [[1e6, 0, 0]]])
    >>> box, n = robust_extent(pts)
    >>> n, bool(box[1, 0] < 11)
    (1, True)
    """
    pts = np.asarray(points, dtype=np.float64)
    lo, hi = np.quantile(pts, [tail, 1 - tail], axis=0)
    margin = np.maximum(hi - lo, 1.0)
    inside = ((pts >= lo - margin) & (pts <= hi + margin)).all(axis=1)
    core = pts[inside]
    return np.stack([core.min(axis=0), core.max(axis=0)]), int(len(pts) - len(core))
