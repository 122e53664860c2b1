"""The world a command plans in, built from its map options as the API builds it."""

from __future__ import annotations

import argparse

from planner.errors import PlannerError
from planner.lattice import Lattice

BAG_OPTIONS = ("topic", "fixed_frame", "max_clouds")


def bag_options(a: argparse.Namespace) -> dict:
    """The bag reader's options given on the command line (``topic``, ``fixed_frame``,
    ``max_clouds``), for :func:`planner.io.load_obstacles`."""
    return {k: v for k in BAG_OPTIONS if (v := getattr(a, k, None)) is not None}


def map_source(a: argparse.Namespace):
    """The map argument, or the obstacles read from it when bag options are given (they
    belong to the bag reader, not to the world)."""
    bag = bag_options(a)
    if not bag:
        return a.map
    from planner.io import load_obstacles  # lazy: scipy

    return load_obstacles(a.map, a.format, **bag)


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
    world = build_world(map_source(a), lattice, cell_volume=a.cell_volume, radius=a.radius,
                        bounds=a.bounds, format=a.format, unknown=a.unknown)
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
