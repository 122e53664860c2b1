"""Suite definitions: a small TOML file expanded into world configurations and runs.

Example::

    name = "quick"
    seed = 1
    queries = 6                      # per map x cell volume x radius
    lattices = ["cubic", "bcc", "fcc", "mcc", "hex"]
    neighbors = ["face", "full"]
    methods = ["astar", "theta"]     # lattice methods; "explore": exploration runs
                                     # (planner.bench.explore_rows, sensor in [explore])
    min_distance = 0.3               # start-goal distance, fraction of the box diagonal
    rotation = "yaw"                 # "none" | "yaw" (about z) | "so3": the map and its
    rotations = 8                    # queries turn together; same sample for every lattice

    [ompl]                           # optional continuous baseline
    planners = ["rrtconnect"]
    time = 0.5                       # seconds per run
    seeds = [0, 1]
    lattice = "cubic"                # whose voxel world OMPL checks validity against

    [[maps]]
    path = "office"                  # a bundled map name, or a file relative to the suite
                                     # file's folder, then to the current folder
    cell_volumes = [0.008]
    radii = [0.2]
    # scenarios = "../shared/data/warframe/Simple.3dmap.3dscen"   # instead of sampling
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from planner.bench.schema import SuiteError, check_suite_table, label_ok, parse_suite
from planner.budget import require
from planner.errors import PlannerError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.lattice.paper import NAMED_LATTICES_2D

SUITES = Path(__file__).resolve().parent / "suites"
"""Bundled suites (package data): ``planner bench quick`` reads ``SUITES / "quick.toml"``."""


@dataclass(frozen=True)
class MapSpec:
    path: str
    cell_volumes: tuple[float, ...]
    radii: tuple[float, ...]
    scenarios: str | None = None
    queries: int | None = None


@dataclass(frozen=True)
class Suite:
    name: str
    maps: tuple[MapSpec, ...]
    lattices: tuple[str, ...] = NAMED_LATTICES
    neighbors: tuple[str, ...] = ("face", "full")
    methods: tuple[str, ...] = ("astar",)
    queries: int = 10
    seed: int = 0
    min_distance: float = 0.3
    ompl_planners: tuple[str, ...] = ()
    ompl_time: float = 1.0
    ompl_seeds: tuple[int, ...] = (0,)
    ompl_lattice: str = "cubic"
    rotation: str = "none"
    rotations: int = 1
    kind: str = "planning"
    paper: dict = field(default_factory=dict)
    explore: dict = field(default_factory=dict)
    source: str = ""
    skipped: tuple[str, ...] = field(default=())


def _resolve(p: str, base: Path) -> Path | None:
    """A map path relative to the suite's folder, then the current folder, else a bundled
    map name (``office``); None when absent."""
    from planner.maps import MAPS, map_path, resolve  # lazy: scipy

    for root in (base, Path.cwd()):
        q = (root / p).resolve()
        if q.exists():
            return q
    stem = p[:-4] if p.endswith(".ply") else p
    if stem in MAPS:
        return map_path(stem)
    q = resolve(p)  # the bundled 2D map (floorplan)
    return q if q != Path(p) and q.exists() else None


def _check_methods(path: Path, methods: tuple[str, ...], planners: tuple[str, ...]) -> None:
    from planner.ompl import PLANNERS  # lazy: numba, scipy
    from planner.search import METHODS  # lazy: numba, scipy

    for m in methods:
        if m not in (*METHODS, "explore"):
            raise SuiteError(f"{path}: unknown method {m!r} (lattice methods: "
                             f"{', '.join(METHODS)}, or explore; OMPL planners go in "
                             f"[ompl] planners)")
    for p in planners:
        if p not in PLANNERS:
            raise SuiteError(f"{path}: unknown OMPL planner {p!r} (known: "
                             f"{', '.join(sorted(PLANNERS))})")


def load_suite(name_or_path: str) -> Suite:
    """Read a suite by bundled name (``quick``, ``paper``, ``full``) or TOML path.

    Maps whose files are absent (e.g. ``../shared/data`` on a fresh clone) are skipped
    and listed in ``Suite.skipped`` rather than failing the whole suite.
    """
    path = Path(name_or_path)
    if not path.suffix and not path.is_file():
        path = SUITES / f"{name_or_path}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in SUITES.glob("*.toml")))
        raise SuiteError(f"{name_or_path}: no such suite (bundled: {known})")
    raw = parse_suite(path)
    check_suite_table(path, raw)
    base = path.parent
    maps, skipped = [], []
    try:
        for m in raw.get("maps", []):
            p = _resolve(m["path"], base)
            if p is None:
                skipped.append(m["path"])
                continue
            scen = None
            if "scenarios" in m:
                s = _resolve(m["scenarios"], base)
                if s is None:
                    skipped.append(m["scenarios"])
                    continue
                scen = str(s)
            maps.append(MapSpec(
                path=str(p),
                cell_volumes=tuple(float(v) for v in m.get("cell_volumes", [m.get("cell_volume")])),
                radii=tuple(float(r) for r in m.get("radii", [m.get("radius", 0.0)])),
                scenarios=scen,
                queries=m.get("queries"),
            ))
        ompl = raw.get("ompl", {})
        suite = Suite(
            name=str(raw.get("name", _label(path.stem))),
            maps=tuple(maps),
            lattices=tuple(raw.get("lattices", NAMED_LATTICES)),
            neighbors=tuple(raw.get("neighbors", ("face", "full"))),
            methods=tuple(raw.get("methods", ("astar",))),
            queries=int(raw.get("queries", 10)),
            seed=int(raw.get("seed", 0)),
            min_distance=float(raw.get("min_distance", 0.3)),
            ompl_planners=tuple(ompl.get("planners", ())),
            ompl_time=float(ompl.get("time", 1.0)),
            ompl_seeds=tuple(int(s) for s in ompl.get("seeds", (0,))),
            ompl_lattice=str(ompl.get("lattice", "cubic")),
            rotation=str(raw.get("rotation", "none")),
            rotations=int(raw.get("rotations", 1)),
            kind=str(raw.get("kind", "planning")),
            paper=dict(raw.get("paper", {})),
            explore=dict(raw.get("explore", {})),
            source=str(path),
            skipped=tuple(skipped),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise SuiteError(f"{path}: bad suite entry: {exc}") from None
    for lat in (*suite.lattices, suite.ompl_lattice):
        if lat not in NAMED_LATTICES + NAMED_LATTICES_2D:  # 2D ones for 2D maps
            raise SuiteError(f"{path}: unknown lattice {lat!r}")
    _check_methods(path, suite.methods, suite.ompl_planners)
    from planner.bench.rotations import ROTATION_KINDS  # lazy: scipy

    if suite.rotation not in ROTATION_KINDS:
        raise SuiteError(f"{path}: rotation must be one of {', '.join(ROTATION_KINDS)}, "
                         f"got {suite.rotation!r}")
    if suite.rotations < 1:
        raise SuiteError(f"{path}: rotations must be >= 1, got {suite.rotations}")
    unknown = set(suite.paper) - {"rotations", "volumes", "samples", "seed", "quick"}
    if unknown:
        raise SuiteError(f"{path}: unknown [paper] keys {sorted(unknown)}")
    for m in suite.maps:
        if any(v is None or not 0 < v < math.inf for v in m.cell_volumes):
            raise SuiteError(f"{path}: map {m.path} needs positive cell_volumes")
        if not all(0 <= r < math.inf for r in m.radii):
            raise SuiteError(f"{path}: map {m.path} needs finite radii >= 0")
    _check_size(path, suite)
    for kind in suite.neighbors:
        for lat in suite.lattices:
            try:
                Lattice.named(lat).neighbors(kind)
            except PlannerError as exc:
                raise SuiteError(f"{path}: neighbors {kind!r}: {exc}") from None
    return suite


def _label(stem: str) -> str:
    """A suite file's stem as a label (a name when the suite gives none): characters other
    than letters, digits and ``_ . + - ( )`` and space become ``_``."""
    name = re.sub(r"[^\w .+()-]|\.\.", "_", stem)[:100]
    return name if label_ok(name) else f"suite_{name}"[:100]


def _check_size(path: Path, suite: Suite) -> None:
    """Refuse a suite whose run list (every map x cell volume x radius x rotation x lattice
    x move set x method x query) would not fit the memory budget, before it is listed."""
    methods = max(1, len(suite.methods) + len(suite.ompl_planners) * len(suite.ompl_seeds))
    per_rotation = sum(len(m.cell_volumes) * len(m.radii) * (m.queries or suite.queries)
                       for m in suite.maps) * len(suite.lattices) * len(suite.neighbors)
    runs = float(per_rotation) * suite.rotations * methods
    # a run's task and its result row: a few kB each
    require(runs * 4096, f"{path.name}: the list of {runs:.3g} runs ({suite.rotations} "
            f"rotations)", error=SuiteError)
