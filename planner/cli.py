"""Plan paths on cubic, BCC, FCC, MCC and hex-prism lattices; compare and benchmark them.

Exit status: 0 success, 1 no path found, 2 bad input (one-line message, no traceback),
130 / 143 interrupted by SIGINT / SIGTERM.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import re
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from planner.errors import PlannerError
from planner.lattice import NAMED_LATTICES
from planner.lattice.paper import NAMED_LATTICES_2D

METHODS = "astar, dijkstra, theta, lazy-theta, ompl:<planner>"
PLOT_SUFFIXES = (".png", ".pdf", ".svg")
# options whose values may start with "-" (negative coordinates)
_VECTOR_OPTIONS = ("--start", "--goal", "--bounds", "--generator", "--init")
# options of every command, accepted before or after the command name
_GLOBAL_OPTIONS = ("--memory-budget", "--max-expansions")
_NUMBERISH = re.compile(r"^-[0-9.]")


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Defaults shown only where there is one; required options say so."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if action.required and action.option_strings:
            return f"{text} (required)"
        if action.default is None or action.default is False:
            return text
        return super()._get_help_string(action)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # one line, exit 2, as for every bad input
        self.exit(2, f"{self.prog}: error: {message}\n")


# -- argument types ------------------------------------------------------------------------
def _numbers(text: str, n: int, what: str) -> np.ndarray:
    try:
        v = np.array([float(t) for t in text.replace(" ", "").split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if v.shape != (n,) or not np.isfinite(v).all():
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return v


def _vec3(text: str) -> np.ndarray:
    if text.count(",") == 1:  # x,y on a 2D map (the world checks the map is 2D)
        return _numbers(text, 2, "three finite numbers x,y,z (x,y on a 2D map)")
    return _numbers(text, 3, "three finite numbers x,y,z")


def _bounds(text: str) -> np.ndarray:
    return _numbers(text, 6, "six numbers xmin,ymin,zmin,xmax,ymax,zmax").reshape(2, 3)


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v == math.inf:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _nonneg(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v >= 0 or v == math.inf:
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text!r}")
    return v


def _int_range(lo: int, hi: int | None = None):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if v < lo or (hi is not None and v > hi):
            span = f"at least {lo}" if hi is None else f"in {lo}..{hi}"
            raise argparse.ArgumentTypeError(f"expected an integer {span}, got {text!r}")
        return v
    return parse


def _size(text: str) -> int:
    from planner.budget import parse_size

    try:
        return parse_size(text)
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _map(text: str) -> str:
    """A map file, or a bundled map by name (``office``) from any folder."""
    from planner.maps import resolve

    return str(resolve(text))


def _lattice_list(text: str) -> list[str]:
    names = [s.strip().lower() for s in text.split(",") if s.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected lattice names from {', '.join(NAMED_LATTICES)}")
    bad = [n for n in names if n not in NAMED_LATTICES + NAMED_LATTICES_2D]
    if bad:
        raise argparse.ArgumentTypeError(
            f"unknown lattice {bad[0]!r}; expected names from {', '.join(NAMED_LATTICES)}")
    return names


def _explore_lattices(text: str) -> list[str]:
    return list(NAMED_LATTICES) if text.strip() == "all" else _lattice_list(text)


def _fov(text: str) -> tuple[float, float]:
    h, v = _numbers(text, 2, "field of view")
    if not (0 < h <= 360 and 0 <= v <= 90):
        raise argparse.ArgumentTypeError(f"field of view must be 0<h<=360, 0<=v<=90 degrees, "
                                         f"got {text!r}")
    return float(h), float(v)


def _generator(text: str):
    """A custom lattice: ``"a,b,c;d,e,f;g,h,i"`` (rows of G) or a ``.npy`` file."""
    from planner.lattice import Lattice

    if text.endswith(".npy"):
        try:
            g = np.load(text, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise argparse.ArgumentTypeError(f"{text}: cannot read a matrix: {exc}") from None
    else:
        rows = [r for r in text.split(";") if r.strip()]
        try:
            g = np.array([[float(t) for t in r.split(",")] for r in rows])
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected rows 'a,b,c;d,e,f;g,h,i', got {text!r}") from None
    try:
        return Lattice(g, name="custom")
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


_OUTPUTS = {("plan", "out"): (".csv", ".json", ".tum"),
            ("world", "out"): (".npz", ".ply", ".bt"),
            ("view", "out"): (".html",), ("plan", "view"): (".html",),
            ("compare", "view"): (".html",), ("explore", "view"): (".html",),
            ("plan", "plot"): PLOT_SUFFIXES, ("compare", "plot"): PLOT_SUFFIXES,
            ("explore", "plot"): (".png",),
            ("match-experiment", "plot"): PLOT_SUFFIXES, ("explore", "gif"): (".gif",)}


def _check_output(option: str, text: str, suffixes: tuple[str, ...]) -> None:
    """Refuse an output file that cannot be written, before any work is done."""
    p = Path(text)
    where = f"argument --{option}: {text}"
    if p.suffix.lower() not in suffixes:
        raise PlannerError(f"{where}: unsupported output type {p.suffix or '(none)'!r}; use "
                           f"{', '.join(suffixes)}")
    if p.is_dir():
        raise PlannerError(f"{where}: is a directory")
    parent = p.absolute().parent
    while not parent.exists():  # missing folders are created when writing
        parent = parent.parent
    if not parent.is_dir():
        raise PlannerError(f"{where}: {parent} is not a directory")
    try:  # a real probe: permissions, read-only and virtual file systems (/proc)
        fd, probe = tempfile.mkstemp(prefix=".planner-probe.", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise PlannerError(f"{where}: cannot write into {parent}: {exc.strerror}") from None


# -- parser --------------------------------------------------------------------------------
def _add_world_args(p: argparse.ArgumentParser, *, lattice: bool = True,
                    bag: bool = True) -> None:
    p.add_argument("map", type=_map,
                   help="map file: ROS bag (.bag, rosbag2 folder, .db3, .mcap), LAS/LAZ, "
                        "E57, map_server YAML (+ PGM), saved world (.npz), MovingAI .3dmap, "
                        "PCD, PLY, OctoMap .bt, .npy, text (.xyz/.txt/.dat[.gz|.bz2|.xz]); "
                        "or a bundled map name (office, two_storey, warehouse, forest, "
                        "narrow_passage)")
    if lattice:
        g = p.add_mutually_exclusive_group()
        g.add_argument("--lattice", default=None, choices=NAMED_LATTICES + NAMED_LATTICES_2D,
                       help="named lattice (2D maps: square or hex2d; a saved world keeps its "
                            "own unless another is named); not given: fcc, on a 2D map hex2d")
        g.add_argument("--generator", type=_generator, default=None,
                       help="custom lattice: generator rows 'a,b,c;d,e,f;g,h,i' (columns are "
                            "the basis vectors, metres) or a .npy file")
    p.add_argument("--cell-volume", type=_positive, default=None,
                   help="cell volume in m^3 (default: the map's suggestion or native resolution)")
    p.add_argument("--radius", type=_nonneg, default=None,
                   help="robot radius in metres (default: the map's suggestion; required for "
                        "maps without one)")
    p.add_argument("--bounds", type=_bounds, default=None,
                   help="world box xmin,ymin,zmin,xmax,ymax,zmax (m)")
    p.add_argument("--format", default=None,
                   help="file format instead of the extension: bag, las (LAS/LAZ), e57, "
                        "rosmap (map_server YAML), 3dmap, pcd, ply, bt, npy, xyz (text), or "
                        "poses (a pose list of scans, merged)")
    p.add_argument("--check-source", action="store_true",
                   help="with a saved world: refuse it unless its source map (beside the "
                        "world file or in the current folder) still has the SHA-256 "
                        "recorded at save")
    if bag:
        b = p.add_argument_group("ROS bags")
        b.add_argument("--topic", help="PointCloud2 topic (default: the first in the bag)")
        b.add_argument("--fixed-frame", help="frame the clouds are put into with /tf and "
                                             "/tf_static (default: the root of the tf tree)")
        b.add_argument("--max-clouds", type=_int_range(1), help="read at most this many clouds")
    p.add_argument("--unknown", choices=("blocked", "free"), default=None,
                   help="unknown space: blocked (kept the robot radius away, as obstacles) or "
                        "free (default: blocked when the map says what was observed free, else "
                        "free)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="planner", description=__doc__.splitlines()[0])
    parser.add_argument("--memory-budget", type=_size, default=None,
                        help="bytes one step (inflation, grid, search) may use, e.g. 4G or "
                             "512M; refused in one line above it (default: "
                             "$PLANNER_MEMORY_BUDGET or an eighth of the physical memory); "
                             "any command")
    parser.add_argument("--max-expansions", type=_int_range(1), default=None,
                        help="give up a search after this many expansions (exit 1, status "
                             "'budget'; default: as many as the memory budget holds); any "
                             "command")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("lattices", help="table of lattice properties (the paper's measurements)")
    p.add_argument("--cell-volume", type=_positive, default=1.0, help="m^3")
    p.add_argument("--points", type=_int_range(1000), default=10**6,
                   help="uniform points for the Monte-Carlo columns and the speed")
    p.add_argument("--seed", type=_int_range(0, 2**32 - 1), default=0, help="random seed")
    p.add_argument("--all-columns", action="store_true", help="print every column")

    p = sub.add_parser("stats", help="reproduce the paper's Table I and Figs. 3-5")
    p.add_argument("--out", type=Path, default=Path("results/paper"), help="output folder")
    p.add_argument("--rotations", type=_int_range(1), default=100,
                   help="uniform random rotations for Fig. 5")
    p.add_argument("--volumes", type=_positive, nargs="+", default=[0.125, 0.001],
                   help="cell volumes for Fig. 5, m^3")
    p.add_argument("--table1-volume", type=_positive, default=0.125,
                   help="cell volume of Table I, m^3 (the paper's 0.125)")
    p.add_argument("--samples", type=_int_range(100), default=10**6,
                   help="uniform samples per distribution for Fig. 4")
    p.add_argument("--seed", type=_int_range(0, 2**32 - 1), default=0, help="random seed")
    p.add_argument("--data", type=Path, default=None,
                   help="real data folder (default: ../shared/data)")
    p.add_argument("--quick", action="store_true",
                   help="CI-sized run: 4 rotations, 5e4 samples, scans subsampled to 2e4 points")

    p = sub.add_parser("plan", help="plan a path on a lattice")
    _add_world_args(p)
    p.add_argument("--start", type=_vec3, required=True,
                   help="x,y,z (m; x,y on a 2D map); negatives allowed")
    p.add_argument("--goal", type=_vec3, required=True,
                   help="x,y,z (m; x,y on a 2D map); negatives allowed")
    p.add_argument("--method", default="astar", help=METHODS)
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--corner-cutting", action="store_true", help="check the target cell only")
    p.add_argument("--shortcut", action="store_true", help="shortcut the A* path")
    p.add_argument("--time", type=_positive, default=1.0, help="OMPL time budget (s)")
    p.add_argument("--seed", type=_int_range(0, 2**32 - 1), default=0, help="OMPL seed")
    p.add_argument("--out", help="write the path (.json, .csv, or .tum: a TUM trajectory)")
    p.add_argument("--bag", help="write the path as a ROS 2 bag folder (nav_msgs/msg/Path on "
                                 "/plan; 'robot' extra)")
    p.add_argument("--plot", help="write a figure of the path")
    p.add_argument("--view", help="write an interactive 3D view of the path (.html)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")

    p = sub.add_parser("compare", help="plan the same queries on every lattice (main job)")
    _add_world_args(p, lattice=False, bag=False)
    p.add_argument("--lattices", type=_lattice_list, default=",".join(NAMED_LATTICES),
                   help="comma-separated lattice names")
    p.add_argument("--generator", type=_generator, default=None,
                   help="also compare a custom lattice: rows 'a,b,c;d,e,f;g,h,i' or a .npy")
    p.add_argument("--start", type=_vec3, default=None, help="x,y,z (m); default: map's queries")
    p.add_argument("--goal", type=_vec3, default=None, help="x,y,z (m); default: map's queries")
    p.add_argument("--method", default="astar", help=METHODS)
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--plot", help="write a figure of the paths")
    p.add_argument("--view", help="write an interactive 3D view of the paths (.html)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")

    p = sub.add_parser("world", help="build a planning world once and save it (.npz) for "
                                     "plan and compare")
    _add_world_args(p)
    p.add_argument("--out", required=True,
                   help="output .npz (the world), .ply (blocked and unknown cell centres) "
                        "or .bt (OctoMap tree of the blocked cells; cubic lattice only)")

    p = sub.add_parser("view", help="write an interactive 3D view (one self-contained .html) "
                                    "of a map or saved world and paths")
    _add_world_args(p)
    p.add_argument("--path", action="append", default=[],
                   help="a path file from 'planner plan --out P.json' (repeatable)")
    p.add_argument("--max-cells", type=_int_range(1), default=400_000,
                   help="most cells drawn per layer (hidden interior cells dropped first, "
                        "then uniform decimation)")
    p.add_argument("--out", required=True, help="output .html")

    p = sub.add_parser("explore", help="explore an unknown map with a simulated range sensor, "
                                       "replanning with D* Lite (checked against A*)")
    _add_world_args(p, lattice=False, bag=False)
    p.add_argument("--lattice", default=None, type=_explore_lattices,
                   help="named lattice, comma-separated names, or 'all' (default: fcc)")
    p.add_argument("--start", type=_vec3, required=True, help="x,y,z (m); negatives allowed")
    p.add_argument("--goal", type=_vec3, required=True, help="x,y,z (m); negatives allowed")
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--sensor-range", type=_positive, default=4.0, help="metres")
    p.add_argument("--fov", type=_fov, default=(360.0, 30.0),
                   help="horizontal,vertical field of view in degrees (vertical is +-)")
    p.add_argument("--resolution", type=_positive, default=3.0, help="ray spacing, degrees")
    p.add_argument("--max-steps", type=_int_range(1), default=100_000, help="move budget")
    p.add_argument("--plot", help="summary figure (PNG); with several lattices, one per "
                                  "lattice (name suffixed)")
    p.add_argument("--view", help="interactive 3D view (.html) of the true world and the "
                                  "trajectory; with several lattices, one per lattice")
    p.add_argument("--gif", help="animated GIF of the exploration, one frame per replan "
                                 "(at most --frames); with several lattices, one per lattice")
    p.add_argument("--frames", type=_int_range(1), default=150,
                   help="most replan frames in the GIF (evenly subsampled; 150)")
    p.add_argument("--json", action="store_true", help="print the summaries as JSON")

    p = sub.add_parser("match", help="rigid 6-DOF scan matching on multi-resolution lattice "
                                     "voxel lists (4x4 source -> reference transform)")
    p.add_argument("source", help="source scan (.pcd, .ply, .npy, .xyz, ...)")
    p.add_argument("reference", help="reference scan or map (any point format read)")
    p.add_argument("--lattice", default="fcc", choices=NAMED_LATTICES, help="lattice")
    p.add_argument("--cell-volume", type=_positive, default=0.001, help="finest cell, m^3")
    p.add_argument("--levels", type=_int_range(1, 12), default=4, help="resolutions")
    p.add_argument("--init", type=lambda t: _numbers(t, 6, "six numbers x,y,z,roll,pitch,yaw"),
                   default=None, help="initial pose x,y,z (m),roll,pitch,yaw (degrees)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")

    p = sub.add_parser("match-experiment", help="the paper's Fig. 6: scan-matching errors "
                       "per lattice and the ICP anchor from random initial errors")
    p.add_argument("--data", default="../shared/data", help="data folder of the sources")
    p.add_argument("--sources", default="velodyne,geb079,room",
                   help="comma-separated: velodyne, geb079 (simulated), room (consistency)")
    p.add_argument("--pair", nargs=3, action="append", metavar=("SOURCE", "REFERENCE", "T"),
                   help="an extra pair: two point files and the 4x4 source -> reference "
                        "transform (text); repeatable")
    p.add_argument("--lattices", default=",".join(NAMED_LATTICES), help="comma-separated")
    p.add_argument("--trials", type=_int_range(1), default=6,
                   help="random initial errors (and rotations) per pair")
    p.add_argument("--simulated-pairs", type=_int_range(1), default=1,
                   help="simulated geb079 pairs per separation (0.25, 0.5, 1 m)")
    p.add_argument("--cell-volume", type=_positive, default=0.001, help="finest cell, m^3")
    p.add_argument("--levels", type=_int_range(1, 12), default=4, help="resolutions")
    p.add_argument("--max-offset", type=_positive, default=0.5, help="initial error, m")
    p.add_argument("--max-angle", type=_positive, default=10.0, help="initial error, deg")
    p.add_argument("--seed", type=_int_range(0), default=0, help="seed of the shared draws")
    p.add_argument("--out", default="results/fig6", help="output folder")
    p.add_argument("--plot", default=None, help="box plot (.png, .pdf, .svg; default "
                                                "OUT/fig6.png)")
    p.add_argument("--no-icp", action="store_true", help="leave out the ICP anchor")
    p.add_argument("--resume", action="store_true", help="keep finished rows, run the rest")
    p.add_argument("--force", action="store_true", help="delete finished rows, start again")
    p.add_argument("--no-progress", action="store_true", help="no progress on stderr")

    p = sub.add_parser("bench", help="run a benchmark suite (which lattice for my map?)")
    p.add_argument("suite", help="bundled suite name (quick, paper, full) or a TOML file")
    p.add_argument("--out", default=None, help="output folder (default: results/<suite>)")
    p.add_argument("--jobs", type=_int_range(1), default=1, help="local worker processes")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address tcp://host:port")
    p.add_argument("--resume", action="store_true",
                   help="keep finished rows and the sampled queries, run the rest")
    p.add_argument("--force", action="store_true",
                   help="start again in a folder that already holds results")
    p.add_argument("--no-progress", action="store_true", help="no progress on stderr")
    p.add_argument("--report-only", action="store_true",
                   help="no new runs: summarise the rows already in OUT/results.jsonl")
    return parser


def _join_negative_values(argv: list[str]) -> list[str]:
    """``--start -2.96,-0.05,1`` -> ``--start=-2.96,-0.05,1`` (argparse would read the value
    as an option)."""
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a in _VECTOR_OPTIONS and i + 1 < len(argv) and _NUMBERISH.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def _hoist_global_options(argv: list[str]) -> list[str]:
    """Move :data:`_GLOBAL_OPTIONS` (with their values) in front of the command name, so
    ``planner plan map --memory-budget 2G`` works as ``planner --memory-budget 2G plan``."""
    head, rest, i = [], [], 0
    while i < len(argv):
        a = argv[i]
        if a == "--":
            rest += argv[i:]
            break
        if a.split("=", 1)[0] in _GLOBAL_OPTIONS:
            take = 1 if "=" in a or i + 1 == len(argv) else 2
            head += argv[i:i + take]
            i += take
            continue
        rest.append(a)
        i += 1
    return head + rest


# -- commands ------------------------------------------------------------------------------
def _cmd_lattices(a) -> int:
    from planner.analysis import measure

    rows = measure.lattice_table(cell_volume=a.cell_volume, n_points=a.points, seed=a.seed)
    print(f"cell volume {a.cell_volume:g} m^3; distances and radii in metres; "
          f"nsm = normalised second moment; mean_error = eq. (13) on {a.points} "
          "uniform points; points_per_s = quantize() throughput")
    print(measure.format_table(rows, None if a.all_columns else measure.TABLE_COLUMNS))
    return 0


def _cmd_stats(a) -> int:
    from planner.analysis.paper import reproduce

    return reproduce(a.out, rotations=a.rotations, volumes=a.volumes, samples=a.samples,
                     seed=a.seed, data=a.data, quick=a.quick, table1_volume=a.table1_volume)


def _build(a):
    from planner.world.build import build_world
    from planner.world.file import is_world_file

    # options not given stay None: build_world resolves them from the map, as in the API
    lattice = a.generator if a.generator is not None else a.lattice
    source = a.map
    bag = {k: v for k in ("topic", "fixed_frame", "max_clouds")
           if (v := getattr(a, k, None)) is not None}
    if bag:  # read here: the options belong to the bag reader
        from planner.io import load_obstacles

        source = load_obstacles(a.map, a.format, **bag)
    world = build_world(source, lattice, cell_volume=a.cell_volume, radius=a.radius,
                        bounds=a.bounds, format=a.format, unknown=a.unknown)
    if getattr(a, "check_source", False) and is_world_file(a.map):
        from planner.world.check import check_source

        check_source(world)
    return world, (a.generator.name if a.generator is not None else world.lattice.name
                   or "custom")


def _check_neighbors(lattices, neighbors: str, method: str) -> None:
    """Refuse a bad or oversized move set before the world is built (index-space moves
    do not depend on the cell volume)."""
    from planner.lattice import Lattice

    if method.startswith("ompl") or neighbors in ("face", "full"):
        return
    for lat in lattices:
        if lat is not None:  # None (the map's default lattice) is checked by the search
            (lat if isinstance(lat, Lattice) else Lattice.named(lat)).neighbors(neighbors)


def _check_dim(world, a) -> None:
    """x,y points only on a 2D map: the parser cannot know the map's dimension."""
    for opt in ("start", "goal"):
        v = getattr(a, opt, None)
        if v is not None and len(v) != (3 if world.dim == 3 else len(v)):
            text = ",".join(f"{x:g}" for x in v)
            raise PlannerError(f"argument --{opt}: expected three finite numbers x,y,z, got "
                               f"{text!r} (x,y only on a 2D map)")


def _cmd_plan(a) -> int:
    from planner import planning as api
    from planner.analysis import compare

    _check_neighbors([a.generator if a.generator is not None else a.lattice], a.neighbors,
                     a.method)
    world, label = _build(a)
    _check_dim(world, a)
    res = api.plan(
        world, a.start, a.goal, method=a.method, neighbors=a.neighbors,
        corner_cutting=a.corner_cutting, shortcut=a.shortcut, time_limit=a.time, seed=a.seed,
        max_expansions=a.max_expansions,
    )
    if a.out and a.out.lower().endswith(".tum"):
        from planner.export import write_tum

        write_tum(a.out, res.path)
    elif a.out:
        from planner.path import write_path

        write_path(a.out, res, world, a.start, a.goal)
    if a.bag and res.found:
        from planner.export import write_path_bag

        write_path_bag(a.bag, res.path, frame=getattr(world.obstacles, "frame", None) or "map")
    if a.plot and res.found:
        compare.plot_paths(a.plot, world, {label: res})
    if a.view:
        from planner.view import write_view

        write_view(a.view, world, {label: res.path} if res.found else {}, start=a.start,
                   goal=a.goal)
    print(json.dumps(res.to_dict()) if a.json else api.describe(res, world))
    return 0 if res.found else 1


def _cmd_compare(a) -> int:
    from planner.analysis import compare
    from planner.world.file import is_world_file, load_world

    lattices = list(a.lattices) + ([a.generator] if a.generator is not None else [])
    radius = a.radius
    if is_world_file(a.map):  # one lattice: the saved one
        saved = load_world(a.map)
        if a.check_source:
            from planner.world.check import check_source

            check_source(saved)
        lattices = [saved.lattice]
        radius = saved.radius if radius is None else radius
    _check_neighbors(lattices, a.neighbors, a.method)
    rows = compare.compare(
        a.map, lattices=lattices, cell_volume=a.cell_volume, radius=radius, bounds=a.bounds,
        start=a.start, goal=a.goal, method=a.method, neighbors=a.neighbors, plot=a.plot,
        progress=not a.json and sys.stderr.isatty(), format=a.format,
        max_expansions=a.max_expansions, unknown=a.unknown, view=a.view,
    )
    print(json.dumps(rows) if a.json else compare.format_rows(rows))
    return 0 if all(r["found"] for r in rows) else 1


def _cmd_world(a) -> int:
    from planner.world.file import save_world

    suffix = Path(a.out).suffix.lower()
    if suffix == ".bt":  # refused before the (long) build when the lattice cannot be a tree
        from planner.export.octomap import check_cubic_name

        check_cubic_name(a.generator if a.generator is not None else a.lattice, a.map)
    world, label = _build(a)
    if suffix == ".npz":
        save_world(world, a.out)
    else:
        from planner.export import write_world_cells

        write_world_cells(a.out, world)
    print(f"{a.out}: {label} world, {world.n_blocked} blocked and {world.n_unknown} unknown "
          f"cells, radius {world.radius:g} m, unknown space {world.unknown_policy}, built in "
          f"{world.build_seconds:.2f} s")
    return 0


def _cmd_explore(a) -> int:
    from planner.analysis.tables import format_table
    from planner.explore import explore

    rows, bad = [], 0
    lattices = a.lattice or [None]  # None: explore's default, resolved from the map
    for name in lattices:
        res = explore(a.map, a.start, a.goal, lattice=name, radius=a.radius,
                      cell_volume=a.cell_volume, bounds=a.bounds, sensor_range=a.sensor_range,
                      fov=a.fov, resolution=a.resolution, neighbors=a.neighbors,
                      max_steps=a.max_steps)
        rows.append(res.summary())
        bad += res.mismatches + res.contacts
        several = len(lattices) > 1
        if a.plot:
            res.plot(_per_lattice(a.plot, name, several))
        if a.gif:
            res.animate(_per_lattice(a.gif, name, several), max_frames=a.frames)
        if a.view:
            _explore_view(_per_lattice(a.view, name, several), a, res)
    print(json.dumps(rows) if a.json else format_table(rows))
    if bad:  # D* Lite disagreed with A* from scratch, or the robot touched the true map
        raise PlannerError(f"{bad} mismatches/contacts: see the table")
    return 0 if all(r["status"] == "reached" for r in rows) else 1


def _explore_view(out: Path, a, res) -> None:
    """The true inflated world of one exploration, its trajectory and its last plan."""
    from planner.view import write_view
    from planner.world.build import build_world

    world = build_world(a.map, res.lattice, cell_volume=a.cell_volume, radius=a.radius,
                        bounds=a.bounds)
    paths = {f"trajectory ({res.status})": res.trajectory}
    if res.paths:
        paths["last plan"] = res.paths[-1]
    write_view(out, world, paths, start=res.start, goal=res.goal,
               title=f"{Path(a.map).name}: exploration on {res.lattice}")


def _cmd_view(a) -> int:
    from planner.view import read_path_file, write_view

    paths = dict(read_path_file(p) for p in a.path)  # bad files refused before the build
    world, label = _build(a)
    write_view(a.out, world, paths, max_cells=a.max_cells)
    print(f"{a.out}: {label} world, {world.n_blocked} blocked and {world.n_unknown} unknown "
          f"cells, {len(paths)} path(s)")
    return 0


def _per_lattice(out: str, name: str, several: bool) -> Path:
    """The output file of one lattice's run: ``out`` itself, or suffixed by the name."""
    p = Path(out)
    return p.with_name(f"{p.stem}_{name}{p.suffix}") if several else p


def _cmd_match(a) -> int:
    from planner.match.cli_run import run_match

    return run_match(a.source, a.reference, lattice=a.lattice, cell_volume=a.cell_volume,
                     levels=a.levels, init=a.init, as_json=a.json)


def _cmd_match_experiment(a) -> int:
    from planner.match.cli_run import run_match_experiment

    return run_match_experiment(a)


def _cmd_bench(a) -> int:
    from planner.bench.session import run_suite

    return run_suite(a.suite, out=a.out, jobs=a.jobs, scheduler=a.scheduler, resume=a.resume,
                     progress=not a.no_progress, report_only=a.report_only,
                     force=a.force)


_COMMANDS = {"lattices": _cmd_lattices, "stats": _cmd_stats, "plan": _cmd_plan,
             "compare": _cmd_compare, "world": _cmd_world,
             "explore": _cmd_explore, "match": _cmd_match, "view": _cmd_view,
             "match-experiment": _cmd_match_experiment,
             "bench": _cmd_bench}


def _os_error(exc: OSError) -> str:
    """``path: reason`` of an OS error on one line (``[Errno 28] No space left ...``)."""
    what = exc.strerror or str(exc) or type(exc).__name__
    where = exc.filename if exc.filename is not None else ""
    if exc.filename2 is not None:
        where = f"{where} -> {exc.filename2}"
    return " ".join(f"{where}: {what}".split()) if where else " ".join(what.split())


def _leave(status: int) -> None:
    """End the program now after an interrupt: flush the streams and ``os._exit``, with no
    interpreter finalisation. Finalising tears down numba's compiler state (LLVM) and the
    modules while an interrupted compilation, cache load or a worker thread inside a
    ``nogil`` kernel may still hold them, which is where a Ctrl-C can turn into a crash."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(status)


def main(argv: list[str] | None = None) -> int:
    """The ``planner`` program (``argv`` None: ``sys.argv[1:]``, and an interrupted run
    ends the process at once with 130 / 143; with ``argv`` given it returns the status)."""
    standalone = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    a = build_parser().parse_args(_hoist_global_options(_join_negative_values(argv)))
    if a.memory_budget is not None:  # the one budget model reads it (and so do workers)
        from planner.budget import ENV

        os.environ[ENV] = str(a.memory_budget)
    # numpy warnings are shown only when the command succeeds: an error is one line
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        try:
            for (cmd, option), suffixes in _OUTPUTS.items():
                if a.command == cmd and getattr(a, option, None):
                    _check_output(option, getattr(a, option), suffixes)
            with np.errstate(all="warn"):
                status = _COMMANDS[a.command](a)
        except PlannerError as exc:
            print(f"planner: error: {' '.join(str(exc).split())}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            import signal

            signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C: no traceback
            print("planner: interrupted", file=sys.stderr)
            if standalone:
                _leave(130)
            return 130
        except BrokenPipeError:  # output piped into `head`: stop quietly, as Unix tools do
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 141
        except OSError as exc:  # a full disk, a read-only folder, ...: outputs are atomic,
            print(f"planner: error: {_os_error(exc)}", file=sys.stderr)  # nothing is half-
            return 2  # written (fsutil.atomic_path removes its temporary file)
    for w in caught:
        with contextlib.suppress(Exception):
            print(f"planner: warning: {w.message}", file=sys.stderr)
    if standalone and status in (130, 143):  # bench stopped by SIGINT / SIGTERM
        _leave(status)
    return status


if __name__ == "__main__":
    sys.exit(main())
