"""The world a command plans in, built from its map options as the API builds it."""

from __future__ import annotations

import argparse
import sys
import time

from planner.errors import PlannerError
from planner.lattice import Lattice
from planner.maps import resolve

BAG_OPTIONS = ("topic", "fixed_frame", "max_clouds")


def bag_options(a: argparse.Namespace) -> dict:
    """The bag reader's options given on the command line (``topic``, ``fixed_frame``,
    ``max_clouds``), for :func:`planner.io.load_obstacles`."""
    return {k: v for k in BAG_OPTIONS if (v := getattr(a, k, None)) is not None}


def map_source(a: argparse.Namespace):
    """The map argument, or the obstacles read from it when it is a bag (read here with
    its options and a progress line, and what was read said on stderr) or a sensor
    ``--origin`` is given (it belongs to the reader, not to the world)."""
    origin = getattr(a, "origin", None)
    if not reads_source(a):
        return a.map
    from planner.io import load_obstacles, with_origin  # lazy: scipy
    from planner.world.file import is_world_file  # lazy: numba, scipy

    path = resolve(a.map)
    if origin is not None and is_world_file(path):
        raise PlannerError(f"argument --origin: {a.map} is a saved world; give the scan "
                           f"itself")
    bag = _is_bag(a)
    obst = load_obstacles(path, a.format, **bag_options(a), **({"progress": True} if bag
                                                                 else {}))
    if obst.read:
        print(f"planner: {describe_read(obst)}", file=sys.stderr)
    return obst if origin is None else with_origin(obst, origin)


def describe_read(obst) -> str:
    """One line on what a bag read chose: topic, fixed frame, clouds."""
    r = obst.read
    n = len(r["topics"])
    topic = (f"topic {r['topic']}" + ("" if r["topic_given"] else
             f" (the first of {n} PointCloud2 topic{'s' if n > 1 else ''}"
             + (f": {', '.join(r['topics'])}; --topic picks another)" if n > 1 else ")")))
    frame = f"fixed frame {r['fixed_frame']!r}" + (
        "" if r["fixed_frame_given"] else " (the root of the tf tree; --fixed-frame picks "
                                          "another)")
    clouds = f"{r['clouds']} of {r['clouds_in_topic']} clouds" + (
        f" (--max-clouds {r['max_clouds']})" if r["max_clouds"] is not None else "")
    return f"read {obst.source}: {topic}, {frame}, {clouds}, {len(obst.points):,} points"


def _is_bag(a: argparse.Namespace) -> bool:
    from planner.io.load import map_format  # lazy: scipy

    return map_format(resolve(a.map), a.format) == "bag"


def reads_source(a: argparse.Namespace) -> bool:
    """True when :func:`map_source` reads the map itself (a bag, bag options or
    ``--origin``)."""
    return (bool(bag_options(a)) or getattr(a, "origin", None) is not None
            or _is_bag(a))


def trust_check(world, a: argparse.Namespace) -> None:
    """A saved world re-verified against its source map (:mod:`planner.world.trust`):
    required with ``--check-source``, by default when the unchanged source is found, never
    with ``--trust-world``."""
    if getattr(a, "trust_world", False) and not getattr(a, "check_source", False):
        return
    from planner.world.trust import verify_world  # lazy: numba, scipy

    verify_world(world, required=getattr(a, "check_source", False),
                 format=getattr(a, "format", None))


def build(a: argparse.Namespace):
    """The world of a command's map options, and its lattice's name.

    Options not given stay None: :func:`planner.world.build.build_world` resolves them from
    the map, as in the API.
    """
    from planner.world.build import build_world  # lazy: numba, scipy
    from planner.world.file import is_world_file  # lazy: numba, scipy

    lattice = a.generator if a.generator is not None else a.lattice
    t0 = time.perf_counter()
    source = map_source(a)
    read_s = time.perf_counter() - t0
    read = getattr(source, "read", None)
    if read and read_s > 5:  # what comes next can take as long again: say so
        print(f"planner: building the world from {len(source.points):,} points (read in "
              f"{read_s:.0f} s) ...", file=sys.stderr, flush=True)
    world = build_world(source, lattice, cell_volume=a.cell_volume, radius=a.radius,
                        bounds=a.bounds, format=a.format, unknown=a.unknown)
    if source is not a.map:  # read here: the path files hash the map itself
        world.source_file = str(resolve(a.map))
    if read and a.cell_volume is None and a.bounds is None and not source.resolution:
        from planner.world.build import DEFAULT_CELLS  # lazy: numba (loaded by the build)

        print(f"planner: note: cell volume {world.lattice.cell_volume:.4g} m^3 is the "
              f"default for the box of what was read (~{DEFAULT_CELLS:,} cells): it "
              f"changes with --max-clouds, --topic and the bag; give --cell-volume to keep "
              f"it", file=sys.stderr)
    if is_world_file(a.map):
        trust_check(world, a)
    return world, (a.generator.name if a.generator is not None else world.lattice.name
                   or "custom")


def check_neighbors(lattices: list, neighbors: str, method: str) -> None:
    """Refuse a bad or oversized move set before the world is built (index-space moves
    do not depend on the cell volume)."""
    if method.startswith("ompl") or neighbors in ("face", "full"):
        return
    for lat in lattices:
        if lat is not None:  # None (the map's default lattice) is checked by the search
            (lat if isinstance(lat, Lattice) else Lattice.named(lat)).neighbors(neighbors)


def check_dim(world, a: argparse.Namespace) -> None:
    """x,y points only on a 2D map: the parser cannot know the map's dimension."""
    for opt in ("start", "goal"):
        v = getattr(a, opt, None)
        if v is not None and len(v) != (3 if world.dim == 3 else len(v)):
            text = ",".join(f"{x:g}" for x in v)
            raise PlannerError(f"argument --{opt}: expected three finite numbers x,y,z, got "
                               f"{text!r} (x,y only on a 2D map)")
