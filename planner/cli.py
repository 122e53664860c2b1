"""Command line: argument parsing only; the work lives in the library modules.

Exit status: 0 success, 1 no path found, 2 bad input (one-line message, no traceback).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np

from planner.errors import PlannerError

LATTICES = ("cubic", "bcc", "fcc", "mcc", "hex")
METHODS = "astar, dijkstra, theta, lazy-theta, ompl:<planner>"


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, as for every bad input
        self.exit(2, f"{self.prog}: error: {message}\n")


def _vec3(text: str) -> np.ndarray:
    try:
        v = np.array([float(t) for t in text.replace(" ", "").split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected x,y,z, got {text!r}") from None
    if v.shape != (3,) or not np.isfinite(v).all():
        raise argparse.ArgumentTypeError(f"expected three finite numbers x,y,z, got {text!r}")
    return v


def _bounds(text: str) -> np.ndarray:
    msg = f"expected six numbers xmin,ymin,zmin,xmax,ymax,zmax, got {text!r}"
    try:
        v = np.array([float(t) for t in text.replace(" ", "").split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(msg) from None
    if v.shape != (6,) or not np.isfinite(v).all():
        raise argparse.ArgumentTypeError(msg)
    return v.reshape(2, 3)


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _nonneg(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v >= 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text!r}")
    return v


def _add_world_args(p: argparse.ArgumentParser, *, lattice: bool = True) -> None:
    p.add_argument("map", help="map file: .ply .pcd .xyz/.txt/.dat[.gz|.bz2] .npy .bt .3dmap")
    if lattice:
        p.add_argument("--lattice", default="fcc", choices=LATTICES)
    p.add_argument("--cell-volume", type=_positive, default=None,
                   help="cell volume in m^3 (default: the map's native resolution)")
    p.add_argument("--radius", type=_nonneg, default=None, help="robot radius in metres")
    p.add_argument("--bounds", type=_bounds, default=None,
                   help="world box xmin,ymin,zmin,xmax,ymax,zmax (m)")
    p.add_argument("--format", default=None,
                   help="file format instead of the extension: ply, pcd, xyz, npy, bt, 3dmap, "
                        "or poses (a pose list of scans, merged)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="planner", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("lattices", help="table of lattice properties (the paper's measurements)")
    p.add_argument("--cell-volume", type=_positive, default=1.0)
    p.add_argument("--points", type=int, default=10**6, help="points for Monte-Carlo and speed")

    p = sub.add_parser("stats", help="reproduce the paper's figures (benchmarks/paper.py)",
                       add_help=False)
    p.add_argument("args", nargs=argparse.REMAINDER)

    p = sub.add_parser("plan", help="plan a path on a lattice")
    _add_world_args(p)
    p.add_argument("--start", type=_vec3, required=True, help="x,y,z (m)")
    p.add_argument("--goal", type=_vec3, required=True, help="x,y,z (m)")
    p.add_argument("--method", default="astar", help=METHODS)
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--corner-cutting", action="store_true", help="check the target cell only")
    p.add_argument("--shortcut", action="store_true", help="shortcut the A* path")
    p.add_argument("--time", type=_positive, default=1.0, help="OMPL time budget (s)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", help="write the path to .csv or .json")
    p.add_argument("--plot", help="write a figure of the path (.png)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")

    p = sub.add_parser("compare", help="plan the same queries on every lattice (main job)")
    _add_world_args(p, lattice=False)
    p.add_argument("--lattices", default=",".join(LATTICES))
    p.add_argument("--start", type=_vec3, default=None)
    p.add_argument("--goal", type=_vec3, default=None)
    p.add_argument("--method", default="astar", help=METHODS)
    p.add_argument("--neighbors", default="full", help="full, face, face+k or full+k")
    p.add_argument("--plot", help="write a figure of the paths (.png)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")

    p = sub.add_parser("voxels", help="build an (inflated) occupied voxel list and save it")
    _add_world_args(p)
    p.add_argument("--out", required=True, help="output .npz")

    p = sub.add_parser("bench", help="run a benchmark suite", add_help=False)
    p.add_argument("args", nargs=argparse.REMAINDER)
    return parser


def _run_script(name: str, argv: list[str]) -> int:
    """Run benchmarks/<name>.py's main(argv) from the source checkout."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py"
    if not path.is_file():
        raise PlannerError(f"{path} not found: run from a source checkout of lattice planner")
    spec = importlib.util.spec_from_file_location(f"_bench_{name}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return int(mod.main(argv) or 0)


def _cmd_lattices(a) -> int:
    from planner import measure

    rows = measure.lattice_table(cell_volume=a.cell_volume, n_points=a.points)
    print(measure.format_table(rows))
    return 0


def _cmd_plan(a) -> int:
    from planner import api, report

    world = api.build_world(a.map, a.lattice, cell_volume=a.cell_volume,
                            radius=a.radius or 0.0, bounds=a.bounds, format=a.format)
    res = api.plan(
        world, a.start, a.goal, method=a.method, neighbors=a.neighbors,
        corner_cutting=a.corner_cutting, shortcut=a.shortcut, time_limit=a.time, seed=a.seed,
    )
    if a.out:
        report.write_path(a.out, res)
    if a.plot and res.found:
        report.plot_paths(a.plot, world, {a.lattice: res})
    if a.json:
        print(json.dumps(res.to_dict()))
    else:
        print(report.describe(res))
    return 0 if res.found else 1


def _cmd_compare(a) -> int:
    from planner import report

    rows = report.compare(
        a.map, lattices=[s.strip() for s in a.lattices.split(",") if s.strip()],
        cell_volume=a.cell_volume, radius=a.radius, bounds=a.bounds, start=a.start,
        goal=a.goal, method=a.method, neighbors=a.neighbors, plot=a.plot,
        progress=not a.json, format=a.format,
    )
    if a.json:
        print(json.dumps(rows))
    else:
        print(report.format_rows(rows))
    return 0 if all(r["found"] for r in rows) else 1


def _cmd_voxels(a) -> int:
    from planner import api

    world = api.build_world(a.map, a.lattice, cell_volume=a.cell_volume,
                            radius=a.radius or 0.0, bounds=a.bounds, format=a.format)
    world.blocked_voxels().save(a.out)
    print(f"{a.out}: {world.n_blocked} blocked {a.lattice} cells, "
          f"cell volume {world.lattice.cell_volume:.6g} m^3")
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = build_parser()
    scripts = {"stats": "paper", "bench": "suite"}
    if argv and argv[0] in scripts:  # forwarded whole (also --help) to the script's parser
        try:
            return _run_script(scripts[argv[0]], list(argv[1:]))
        except PlannerError as exc:
            print(f"planner: error: {exc}", file=sys.stderr)
            return 2
    a = parser.parse_args(argv)
    try:
        if a.command == "lattices":
            return _cmd_lattices(a)
        if a.command == "plan":
            return _cmd_plan(a)
        if a.command == "compare":
            return _cmd_compare(a)
        if a.command == "voxels":
            return _cmd_voxels(a)
    except PlannerError as exc:
        print(f"planner: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("planner: interrupted", file=sys.stderr)
        return 130
    return 2


if __name__ == "__main__":
    sys.exit(main())
