"""``planner explore``: a simulated robot senses its way to the goal on each lattice."""

from __future__ import annotations

import argparse
from pathlib import Path

from planner.analysis.tables import format_table
from planner.commands.worlds import map_source
from planner.errors import PlannerError


def explore(a: argparse.Namespace) -> int:
    """Explore on each named lattice; print one summary row per lattice. Exit 1 if a robot
    did not reach its goal, 2 if the replanner disagreed with A* or the robot touched the
    map."""
    import json

    from planner.explore import explore as run  # lazy: numba, scipy

    rows, bad = [], 0
    lattices = a.lattice or [None]  # None: explore's default, resolved from the map
    source = map_source(a)  # a bag is read once, with its topic and frame
    if a.format is not None and source is a.map:  # explore reads the map: it needs the format
        from planner.io import load_obstacles  # lazy: scipy

        source = load_obstacles(a.map, a.format)
    for name in lattices:
        res = run(source, a.start, a.goal, lattice=name, radius=a.radius,
                  cell_volume=a.cell_volume, bounds=a.bounds, sensor_range=a.sensor_range,
                  fov=a.fov, resolution=a.resolution, neighbors=a.neighbors,
                  max_steps=a.max_steps, progress=not a.json, replanner=a.replanner)
        rows.append(res.summary())
        bad += res.mismatches + res.contacts
        several = len(lattices) > 1
        if a.plot:
            res.plot(per_lattice(a.plot, name, several))
        if a.gif:
            res.animate(per_lattice(a.gif, name, several), max_frames=a.frames)
        if a.view:
            _view(per_lattice(a.view, name, several), a, res, source)
    print(json.dumps(rows) if a.json else format_table(rows))
    if bad:  # the replanner disagreed with A* from scratch, or the robot touched the true map
        raise PlannerError(f"{bad} mismatches/contacts: see the table")
    return 0 if all(r["status"] == "reached" for r in rows) else 1


def per_lattice(out: str, name: str | None, several: bool) -> Path:
    """The output file of one lattice's run: ``out`` itself, or suffixed by the name."""
    p = Path(out)
    return p.with_name(f"{p.stem}_{name}{p.suffix}") if several else p


def _view(out: Path, a: argparse.Namespace, res, source) -> None:
    """The true inflated world of one exploration, its trajectory and its last plan."""
    from planner.view import write_view  # lazy: numba, scipy
    from planner.world.build import build_world  # lazy: numba, scipy

    world = build_world(source, res.lattice, cell_volume=a.cell_volume, radius=a.radius,
                        bounds=a.bounds)
    paths = {f"trajectory ({res.status})": res.trajectory}
    if res.paths:
        paths["last plan"] = res.paths[-1]
    write_view(out, world, paths, start=res.start, goal=res.goal,
               title=f"{Path(a.map).name}: exploration on {res.lattice}")
