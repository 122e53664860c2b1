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
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from planner.budget import require
from planner.errors import PlannerError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.lattice.paper import NAMED_LATTICES_2D

SUITES = Path(__file__).resolve().parent / "suites"
"""Bundled suites (package data): ``planner bench quick`` reads ``SUITES / "quick.toml"``."""


class SuiteError(PlannerError):
    """A suite file that cannot be run."""


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
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SuiteError(f"{path}: not a valid TOML suite: {exc}") from None
    _check_raw(path, raw)
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
            name=str(raw.get("name", path.stem)),
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


_KEYS = {"": {"name", "seed", "queries", "lattices", "neighbors", "methods", "min_distance",
              "ompl", "maps", "kind", "paper", "rotation", "rotations", "explore"},
         "maps": {"path", "cell_volumes", "cell_volume", "radii", "radius", "scenarios",
                  "queries"},
         "ompl": {"planners", "time", "seeds", "lattice"}}
_LISTS = ("lattices", "neighbors", "methods")


def _check_raw(path: Path, raw: dict) -> None:
    """Refuse unknown keys and values of the wrong type or range, naming the key (a typo
    must not silently fall back to a default)."""
    def bad(key: str, want: str) -> SuiteError:
        return SuiteError(f"{path}: {key!r} must be {want}")

    def unknown(table: dict, where: str) -> None:
        extra = sorted(set(table) - _KEYS[where])
        if extra:
            at = f" in [{where}]" if where else ""
            raise SuiteError(f"{path}: unknown key {extra[0]!r}{at} (known: "
                             f"{', '.join(sorted(_KEYS[where]))})")

    unknown(raw, "")
    for key, lo, hi in (("queries", 1, 10**6), ("seed", 0, 2**32 - 1),
                        ("rotations", 1, 10**6)):
        v = raw.get(key, lo)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise bad(key, f"an integer in {lo}..{hi}")
    paper = raw.get("paper", {})
    if not isinstance(paper, dict):
        raise bad("paper", "a [paper] table")
    for key, lo in (("rotations", 1), ("samples", 100), ("seed", 0)):
        v = paper.get(key, lo)
        if isinstance(v, bool) or not isinstance(v, int) or v < lo:
            raise bad(f"paper.{key}", f"an integer >= {lo}")
    vols = paper.get("volumes", [1.0])
    if not isinstance(vols, list) or not vols or not all(
            isinstance(x, int | float) and not isinstance(x, bool) and 0 < x < math.inf
            for x in vols):
        raise bad("paper.volumes", "a non-empty list of positive cell volumes")
    if not isinstance(paper.get("quick", False), bool):
        raise bad("paper.quick", "true or false")
    d = raw.get("min_distance", 0.3)
    if isinstance(d, bool) or not isinstance(d, int | float) or not 0 <= d < math.inf:
        raise bad("min_distance", "a finite number >= 0")
    for key in _LISTS:  # methods may be empty: an OMPL-only suite
        v = raw.get(key, ["x"])
        if not isinstance(v, list) or not (v or key == "methods") or not all(
                isinstance(x, str) for x in v):
            raise bad(key, "a non-empty list of names")
    if not isinstance(raw.get("name", ""), str):
        raise bad("name", "a string")
    if not isinstance(raw.get("kind", "planning"), str) or raw.get("kind") not in (
            None, "planning", "paper"):
        raise bad("kind", '"planning" or "paper"')
    if not isinstance(raw.get("maps", []), list) or not all(
            isinstance(m, dict) for m in raw.get("maps", [])):
        raise bad("maps", "a list of [[maps]] tables")
    for m in raw.get("maps", []):
        unknown(m, "maps")
        if not isinstance(m.get("path"), str):
            raise bad("maps.path", "a string")
        q = m.get("queries", 1)
        if isinstance(q, bool) or not isinstance(q, int) or not 1 <= q <= 10**6:
            raise bad("maps.queries", "an integer in 1..1000000")
    ex = raw.get("explore", {})
    if not isinstance(ex, dict):
        raise bad("explore", "an [explore] table")
    if ex and "explore" not in raw.get("methods", ()):
        raise SuiteError(f"{path}: an [explore] table needs \"explore\" in methods")
    from planner.bench.explore_rows import check_explore_table  # lazy: scipy

    why = check_explore_table(ex)
    if why:
        raise SuiteError(f"{path}: {why}")
    ompl = raw.get("ompl", {})
    if not isinstance(ompl, dict):
        raise bad("ompl", "an [ompl] table")
    unknown(ompl, "ompl")
    t = ompl.get("time", 1.0)
    if isinstance(t, bool) or not isinstance(t, int | float) or not 0 < t < math.inf:
        raise bad("ompl.time", "a positive number of seconds")
    seeds = ompl.get("seeds", [0])
    if not isinstance(seeds, list) or not all(
            isinstance(x, int) and not isinstance(x, bool) and 0 <= x < 2**32 for x in seeds):
        raise bad("ompl.seeds", "a list of integers in 0..4294967295")
