"""``planner plan`` (one path) and ``planner compare`` (the same queries on every lattice)."""

from __future__ import annotations

import argparse
import json

from planner import planning as api
from planner.analysis import compare as comparison
from planner.commands.worlds import (
    build,
    check_dim,
    check_neighbors,
    map_source,
    reads_source,
    trust_check,
)
from planner.export import write_path_bag, write_tum
from planner.lattice import NAMED_LATTICES
from planner.path import write_path


def plan(a: argparse.Namespace) -> int:
    """Plan one path; write it, its figure, view or bag when asked. Exit 1 if none found."""
    check_neighbors([a.generator if a.generator is not None else a.lattice], a.neighbors,
                    a.method)
    world, label = build(a)
    check_dim(world, a)
    res = api.plan(
        world, a.start, a.goal, method=a.method, neighbors=a.neighbors,
        corner_cutting=a.corner_cutting, shortcut=a.shortcut, time_limit=a.time, seed=a.seed,
        max_expansions=a.max_expansions,
    )
    if a.out and a.out.lower().endswith(".tum"):
        write_tum(a.out, res.path)
    elif a.out:
        write_path(a.out, res, world, a.start, a.goal)
    if a.bag and res.found:
        write_path_bag(a.bag, res.path, frame=getattr(world.obstacles, "frame", None) or "map")
    if a.plot and res.found:
        comparison.plot_paths(a.plot, world, {label: res})
    if a.view:
        from planner.view import write_view  # lazy: numba, scipy

        write_view(a.view, world, {label: res.path} if res.found else {}, start=a.start,
                   goal=a.goal)
    print(json.dumps({**res.to_dict(), "warnings": api.world_warnings(world)}) if a.json
          else api.describe(res, world))
    return 0 if res.found else 1


def compare(a: argparse.Namespace) -> int:
    """Plan the same queries on every lattice and print one row per lattice. Exit 1 if any
    query found no path."""
    from planner.world.file import is_world_file, load_world  # lazy: numba, scipy

    # --lattices not given: every named lattice of the map's dimension (2D: square, hex2d)
    lattices = (list(a.lattices) if a.lattices is not None else
                None if a.generator is None else list(NAMED_LATTICES))
    lattices = lattices if a.generator is None else lattices + [a.generator]
    radius = a.radius
    if is_world_file(a.map):  # one lattice: the saved one
        saved = load_world(a.map)
        trust_check(saved, a)
        lattices = [saved.lattice]
        radius = saved.radius if radius is None else radius
    check_neighbors(lattices or list(NAMED_LATTICES), a.neighbors, a.method)
    rows = comparison.compare(
        a.map, lattices=lattices, cell_volume=a.cell_volume, radius=radius, bounds=a.bounds,
        start=a.start, goal=a.goal, method=a.method, neighbors=a.neighbors, plot=a.plot,
        plot_query=a.plot_query, progress=not a.json, format=a.format,
        max_expansions=a.max_expansions,
        unknown=a.unknown, view=a.view, source=map_source(a) if reads_source(a) else None,
    )
    print(json.dumps(rows) if a.json else comparison.format_rows(rows))
    return 0 if all(r["found"] for r in rows) else 1
