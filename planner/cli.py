"""Plan paths on cubic, BCC, FCC, MCC and hex-prism lattices; compare and benchmark them.

Exit status: 0 success, 1 no path found, 2 bad input (one-line message, no traceback),
130 / 143 interrupted by SIGINT / SIGTERM.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import warnings
from pathlib import Path

import numpy as np

from planner import argtypes as T
from planner._interrupt import Terminated, install_sigint, install_sigterm
from planner.budget import ENV
from planner.commands.outputs import check_outputs
from planner.errors import PlannerError
from planner.fsutil import staged_outputs
from planner.lattice import NAMED_LATTICES
from planner.lattice.paper import NAMED_LATTICES_2D

METHODS = "astar, dijkstra, theta, lazy-theta, weighted-theta, ompl:<planner>"


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Defaults shown only where there is one; required options say so."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if action.required and action.option_strings:
            return f"{text} (required)"
        if action.default is None or action.default is False:
            return text
        return super()._get_help_string(action)


class _TableHelpFormatter(_HelpFormatter, argparse.RawDescriptionHelpFormatter):
    """An epilog printed as written (a table of keys)."""


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # one line, exit 2, as for every bad input
        self.exit(2, f"{self.prog}: error: {message}\n")


# -- parser --------------------------------------------------------------------------------
def _add_bag_args(p: argparse.ArgumentParser) -> None:
    """The bag reader's options (``--topic``, ``--fixed-frame``, ``--max-clouds``)."""
    b = p.add_argument_group("ROS bags")
    b.add_argument("--topic", help="PointCloud2 topic (default: the first in the bag)")
    b.add_argument("--fixed-frame", help="frame the clouds are put into with /tf and "
                                         "/tf_static (default: the root of the tf tree)")
    b.add_argument("--max-clouds", type=T.int_range(1), help="read at most this many clouds")


def _add_world_args(p: argparse.ArgumentParser, *, lattice: bool = True,
                    unknown: bool = True) -> None:
    p.add_argument("map", type=T.map_file,
                   help="map file: ROS bag (.bag, rosbag2 folder, .db3, .mcap), LAS/LAZ, "
                        "E57, map_server YAML (+ PGM), saved world (.npz), MovingAI .3dmap, "
                        "PCD, PLY, OctoMap .bt, .npy (x,y,z first), KITTI .bin, text "
                        "(.xyz/.txt/.dat[.gz|.bz2|.xz]); "
                        "or a bundled map name (office, two_storey, warehouse, forest, "
                        "narrow_passage; 2D: floorplan)")
    if lattice:
        g = p.add_mutually_exclusive_group()
        g.add_argument("--lattice", default=None, choices=NAMED_LATTICES + NAMED_LATTICES_2D,
                       help="named lattice (2D maps: square or hex2d; a saved world keeps its "
                            "own unless another is named); not given: fcc, on a 2D map hex2d")
        g.add_argument("--generator", type=T.generator, default=None,
                       help="custom lattice: generator rows 'a,b,c;d,e,f;g,h,i' (columns are "
                            "the basis vectors, metres) or a .npy file")
    p.add_argument("--cell-volume", type=T.positive, default=None,
                   help="cell volume in m^3 (default: the map's suggestion or native resolution)")
    p.add_argument("--radius", type=T.nonneg, default=None,
                   help="robot radius in metres (default: the map's suggestion; required for "
                        "maps without one)")
    p.add_argument("--bounds", type=T.bounds, default=None,
                   help="world box xmin,ymin,zmin,xmax,ymax,zmax (m)")
    p.add_argument("--format", default=None,
                   help="file format instead of the extension: bag, las (LAS/LAZ), e57, "
                        "rosmap (map_server YAML), 3dmap, pcd, ply, bt, npy, kitti (.bin), "
                        "xyz (text), or "
                        "poses (a pose list of scans, merged: one line per scan, "
                        "'SCAN x y z qx qy qz qw' or 'SCAN' and 16 numbers of the 4x4 "
                        "sensor-to-world matrix; # comments; paths relative to the list)")
    p.add_argument("--check-source", action="store_true",
                   help="with a saved world: refuse it unless its source map (beside the "
                        "world file, in the current folder or bundled) still has the "
                        "SHA-256 recorded at save and gives the same cells (rebuilt and "
                        "compared; done by default whenever that source is found)")
    p.add_argument("--trust-world", action="store_true",
                   help="with a saved world: skip the default re-check against its source "
                        "map (the world is then trusted by its digest, which catches damage, "
                        "not edits)")
    _add_bag_args(p)
    if not unknown:  # explore: the robot itself decides what unknown space is
        return
    p.add_argument("--origin", type=T.vec3, default=None,
                   help="x,y,z (m): the sensor position of a single scan (a point cloud), "
                        "in its frame: free space is ray-cast from it and space it never saw "
                        "is unknown (blocked). A PCD's own non-default VIEWPOINT and an E57 "
                        "station pose are used without it; several scans: --format poses")
    p.add_argument("--unknown", choices=("blocked", "free"), default=None,
                   help="unknown space: blocked (kept the robot radius away, as obstacles) or "
                        "free (default: blocked when the map says what was observed free, else "
                        "free)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="planner", description=__doc__.splitlines()[0])
    parser.add_argument("--memory-budget", type=T.size, default=None,
                        help="bytes one step (inflation, grid, search) may use, e.g. 4G or "
                             "512M; refused in one line above it (default: "
                             "$PLANNER_MEMORY_BUDGET or an eighth of the physical memory); "
                             "any command")
    parser.add_argument("--max-expansions", type=T.int_range(1), default=None,
                        help="give up a search after this many expansions (exit 1, status "
                             "'budget'; default: as many as the memory budget holds); any "
                             "command")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("lattices", help="table of lattice properties (the paper's measurements)")
    p.add_argument("--cell-volume", type=T.positive, default=1.0, help="m^3")
    p.add_argument("--points", type=T.int_range(1000), default=10**6,
                   help="uniform points for the Monte-Carlo columns and the speed")
    p.add_argument("--seed", type=T.int_range(0, 2**32 - 1), default=0, help="random seed")
    p.add_argument("--all-columns", action="store_true", help="print every column")

    p = sub.add_parser("stats", help="reproduce the paper's Table I and Figs. 3-5")
    p.add_argument("--out", type=Path, default=Path("results/paper"), help="output folder")
    p.add_argument("--rotations", type=T.int_range(1), default=100,
                   help="uniform random rotations for Fig. 5")
    p.add_argument("--volumes", type=T.positive, nargs="+", default=[0.125, 0.001],
                   help="cell volumes for Fig. 5, m^3")
    p.add_argument("--table1-volume", type=T.positive, default=0.125,
                   help="cell volume of Table I, m^3 (the paper's 0.125)")
    p.add_argument("--samples", type=T.int_range(100), default=10**6,
                   help="uniform samples per distribution for Fig. 4")
    p.add_argument("--seed", type=T.int_range(0, 2**32 - 1), default=0, help="random seed")
    p.add_argument("--data", type=Path, default=None,
                   help="real data folder (default: ../shared/data)")
    p.add_argument("--quick", action="store_true",
                   help="CI-sized run: 4 rotations, 5e4 samples, scans subsampled to 2e4 points")

    p = sub.add_parser("plan", help="plan a path on a lattice")
    _add_world_args(p)
    p.add_argument("--start", type=T.vec3, required=True,
                   help="x,y,z (m; x,y on a 2D map); negatives allowed")
    p.add_argument("--goal", type=T.vec3, required=True,
                   help="x,y,z (m; x,y on a 2D map); negatives allowed")
    p.add_argument("--method", default="astar", help=METHODS)
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--corner-cutting", action="store_true", help="check the target cell only")
    p.add_argument("--shortcut", action="store_true", help="shortcut the A* path")
    p.add_argument("--time", type=T.positive, default=1.0, help="OMPL time budget (s)")
    p.add_argument("--seed", type=T.int_range(0, 2**32 - 1), default=0, help="OMPL seed")
    p.add_argument("--out", help="write the path (.json, .csv, or .tum: a TUM trajectory, "
                                 "one 'stamp x y z qx qy qz qw' line per waypoint, stamped "
                                 "with the arc length to it at 1 m/s)")
    p.add_argument("--bag", help="write the path as a ROS 2 bag folder (nav_msgs/msg/Path on "
                                 "/plan; 'robot' extra)")
    p.add_argument("--plot", help="write a figure of the path")
    p.add_argument("--view", help="write an interactive 3D view of the path (.html)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")

    p = sub.add_parser("compare", help="plan the same queries on every lattice (main job)")
    _add_world_args(p, lattice=False)
    p.add_argument("--lattices", type=T.lattice_list, default=None,
                   help="comma-separated lattice names (default: cubic,bcc,fcc,mcc,hex; on a "
                        "2D map square,hex2d)")
    p.add_argument("--generator", type=T.generator, default=None,
                   help="also compare a custom lattice: rows 'a,b,c;d,e,f;g,h,i' or a .npy")
    p.add_argument("--start", type=T.vec3, default=None, help="x,y,z (m); default: map's queries")
    p.add_argument("--goal", type=T.vec3, default=None, help="x,y,z (m); default: map's queries")
    p.add_argument("--method", default="astar", help=METHODS)
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--plot", help="write a figure of the paths: one row of panels per query "
                                  "(the first 4; the title says which)")
    p.add_argument("--plot-query", type=T.int_range(1), default=None,
                   help="draw only query N (1-based) in --plot and --view (default: --plot "
                        "the first 4, --view query 1)")
    p.add_argument("--view", help="write an interactive 3D view of the paths (.html)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")

    p = sub.add_parser("world", help="build a planning world once and save it (.npz) for "
                                     "plan and compare")
    _add_world_args(p)
    p.add_argument("--out", required=True,
                   help="output .npz (the world), .ply (blocked and unknown cell centres) "
                        "or .bt (an OctoMap of the map's obstacles: occupied, observed free, "
                        "unknown left out, on OctoMap's own voxels of the cell edge)")
    p.add_argument("--bt-cspace", action="store_true",
                   help="with --out X.bt: write the planner's blocked cells (the C-space "
                        "mask: obstacles inflated by the radius, plus blocked unknown space) "
                        "instead of the obstacles; cubic lattice only, half a cell shifted "
                        "(the header says so)")

    p = sub.add_parser("view", help="write an interactive 3D view (one self-contained .html) "
                                    "of a map or saved world and paths")
    _add_world_args(p)
    p.add_argument("--path", action="append", default=[],
                   help="a path file from 'planner plan --out P.json' (repeatable)")
    p.add_argument("--max-cells", type=T.int_range(1), default=400_000,
                   help="most cells drawn per layer (hidden interior cells dropped first, "
                        "then uniform decimation)")
    p.add_argument("--out", required=True, help="output .html")

    p = sub.add_parser("explore", help="explore an unknown map with a simulated range sensor, "
                                       "replanning as it senses (checked against A*)")
    _add_world_args(p, lattice=False, unknown=False)
    p.add_argument("--lattice", default=None, type=T.explore_lattices,
                   help="named lattice, comma-separated names, or 'all' (default: fcc)")
    p.add_argument("--start", type=T.vec3, required=True, help="x,y,z (m); negatives allowed")
    p.add_argument("--goal", type=T.vec3, required=True, help="x,y,z (m); negatives allowed")
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--replanner", default="astar", choices=("astar", "dstar"),
                   help="astar: keep the path until a newly blocked cell touches it, then "
                        "A* (default); dstar: D* Lite repairs")
    p.add_argument("--sensor-range", type=T.positive, default=4.0, help="metres")
    p.add_argument("--fov", type=T.fov, default=(360.0, 30.0),
                   help="horizontal,vertical field of view in degrees (vertical is +-)")
    p.add_argument("--resolution", type=T.positive, default=3.0, help="ray spacing, degrees")
    p.add_argument("--max-steps", type=T.int_range(1), default=100_000, help="move budget")
    p.add_argument("--plot", help="summary figure (PNG); with several lattices, one per "
                                  "lattice (name suffixed)")
    p.add_argument("--view", help="interactive 3D view (.html) of the true world and the "
                                  "trajectory; with several lattices, one per lattice")
    p.add_argument("--gif", help="animated GIF of the exploration, one frame per replan "
                                 "(at most --frames); with several lattices, one per lattice")
    p.add_argument("--frames", type=T.int_range(1), default=150,
                   help="most replan frames in the GIF (evenly subsampled; 150)")
    p.add_argument("--json", action="store_true", help="print the summaries as JSON")

    p = sub.add_parser("match", help="rigid 6-DOF scan matching on multi-resolution lattice "
                                     "voxel lists (4x4 source -> reference transform)")
    p.add_argument("source", help="source scan (.pcd, .ply, .npy, .xyz, ...)")
    p.add_argument("reference", help="reference scan or map (any point format read)")
    p.add_argument("--lattice", default="fcc", choices=NAMED_LATTICES, help="lattice")
    p.add_argument("--cell-volume", type=T.positive, default=0.001, help="finest cell, m^3")
    p.add_argument("--levels", type=T.int_range(1, 12), default=4, help="resolutions")
    p.add_argument("--init", type=T.pose6,
                   default=None, help="initial pose x,y,z (m),roll,pitch,yaw (degrees)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")

    p = sub.add_parser("match-experiment", help="the paper's Fig. 6: scan-matching errors "
                       "per lattice and registration anchor (GICP) from random initial "
                       "errors, per regime")
    p.add_argument("--data", default="../shared/data", help="data folder of the sources")
    p.add_argument("--sources", default="velodyne,geb079,room",
                   help="comma-separated: velodyne, geb079 (simulated), room (consistency)")
    p.add_argument("--pair", nargs=3, action="append", metavar=("SOURCE", "REFERENCE", "T"),
                   help="an extra pair: two point files and the 4x4 source -> reference "
                        "transform (text); repeatable")
    p.add_argument("--lattices", default=",".join(NAMED_LATTICES), help="comma-separated")
    p.add_argument("--anchors", default=None,
                   help="comma-separated registration anchors: gicp, gicp-c2f, plane-icp "
                        "(default: all when the 'match' extra is installed)")
    p.add_argument("--regimes", default="default",
                   help="comma-separated: default (0.5 m, 10 deg, or --max-offset/--max-angle), "
                        "far (2 m, 45 deg), overlap (about 40%%), sparse (2,000 points), or "
                        "all")
    p.add_argument("--trials", type=T.int_range(1), default=6,
                   help="random initial errors (and rotations) per pair")
    p.add_argument("--simulated-pairs", type=T.int_range(1), default=1,
                   help="simulated geb079 pairs per separation (0.25, 0.5, 1 m)")
    p.add_argument("--cell-volume", type=T.positive, default=0.001, help="finest cell, m^3")
    p.add_argument("--levels", type=T.int_range(1, 12), default=4, help="resolutions")
    p.add_argument("--max-offset", type=T.positive, default=0.5, help="initial error, m")
    p.add_argument("--max-angle", type=T.positive, default=10.0, help="initial error, deg")
    p.add_argument("--seed", type=T.int_range(0), default=0, help="seed of the shared draws")
    p.add_argument("--out", default="results/fig6", help="output folder")
    p.add_argument("--plot", default=None, help="box plot (.png, .pdf, .svg; default "
                                                "OUT/fig6.png)")
    p.add_argument("--no-icp", action="store_true", help="leave out the registration anchors")
    p.add_argument("--resume", action="store_true", help="keep finished rows, run the rest")
    p.add_argument("--force", action="store_true", help="delete finished rows, start again")
    p.add_argument("--no-progress", action="store_true", help="no progress on stderr")

    from planner.bench.schema import KEYS_HELP  # a table of text; imports nothing heavy

    p = sub.add_parser("bench", help="run a benchmark suite (which lattice for my map?)",
                       formatter_class=_TableHelpFormatter,
                       epilog="suite file keys (TOML):\n\n" + KEYS_HELP)
    p.add_argument("suite", help="bundled suite name (quick, paper, full) or a TOML file")
    p.add_argument("--out", default=None, help="output folder (default: results/<suite>)")
    p.add_argument("--jobs", type=T.int_range(1), default=1, help="local worker processes")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address tcp://host:port")
    p.add_argument("--resume", action="store_true",
                   help="keep finished rows and the sampled queries, run the rest")
    p.add_argument("--force", action="store_true",
                   help="start again in a folder that already holds results")
    p.add_argument("--no-progress", action="store_true", help="no progress on stderr")
    p.add_argument("--report-only", action="store_true",
                   help="no new runs: summarise the rows already in OUT/results.jsonl")
    return parser


# -- dispatch: command -> "module:function" (imported only when the command runs) ---------
_COMMANDS = {"lattices": "tables:lattices", "stats": "tables:stats", "plan": "plan:plan",
             "compare": "plan:compare", "world": "world:world", "view": "world:view",
             "explore": "explore:explore", "match": "runs:match",
             "match-experiment": "runs:match_experiment", "bench": "runs:bench"}


_UNSTAGED = ("bench", "match-experiment", "stats")  # long runs: results kept as they finish


def _command(name: str):
    """The function that does the work of command ``name`` (:mod:`planner.commands`)."""
    import importlib

    module, func = _COMMANDS[name].split(":")
    return getattr(importlib.import_module(f"planner.commands.{module}"), func)


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


def _stopped(exc: BaseException, standalone: bool) -> int:
    """One line for a Ctrl-C (130) or SIGTERM (143); a standalone program ends at once."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second signal: no traceback
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    term = isinstance(exc.__cause__ if isinstance(exc, SystemError) else exc, Terminated)
    print(f"planner: {'terminated' if term else 'interrupted'}", file=sys.stderr)
    if standalone:
        _leave(143 if term else 130)
    return 143 if term else 130


def main(argv: list[str] | None = None) -> int:
    """The ``planner`` program (``argv`` None: ``sys.argv[1:]``, and an interrupted run
    ends the process at once with 130 / 143; with ``argv`` given it returns the status)."""
    standalone = argv is None
    if standalone:  # the process is ours: a Ctrl-C during a kernel's load is not lost
        install_sigint()
        install_sigterm()
    argv = sys.argv[1:] if argv is None else list(argv)
    T.MAP_DIM = 2 if any(T.names_2d_map(x) for x in argv) else None
    try:  # parsing imports the readers (a map name is resolved): a signal may come here
        a = build_parser().parse_args(T.command_line(argv))
    except KeyboardInterrupt as exc:
        return _stopped(exc, standalone)
    if a.memory_budget is not None:  # the one budget model reads it (and so do workers)
        os.environ[ENV] = str(a.memory_budget)
    # numpy warnings are shown only when the command succeeds: an error is one line
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        try:
            check_outputs(a)
            # one command's outputs all or nothing; a suite keeps its own files as it goes
            stage = staged_outputs() if a.command not in _UNSTAGED else contextlib.nullcontext()
            with np.errstate(all="warn"), stage:
                status = _command(a.command)(a)
        except PlannerError as exc:
            print(f"planner: error: {' '.join(str(exc).split())}", file=sys.stderr)
            return 2
        except (KeyboardInterrupt, SystemError) as exc:
            # numba reports a Ctrl-C inside a compiled call as a SystemError caused by it
            if not isinstance(exc.__cause__ if isinstance(exc, SystemError) else exc,
                              KeyboardInterrupt):
                raise
            return _stopped(exc, standalone)
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
