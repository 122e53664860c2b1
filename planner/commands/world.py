"""``planner world`` (build and save a world) and ``planner view`` (an interactive view)."""

from __future__ import annotations

import argparse
from pathlib import Path

from planner.commands.worlds import build
from planner.errors import PlannerError
from planner.export import write_octomap, write_world_cells
from planner.export.octomap import check_cubic_name


def world(a: argparse.Namespace) -> int:
    """Build the world once and write it (.npz), its cells (.ply) or an OctoMap tree (.bt)."""
    from planner.world.file import is_world_file, save_world  # lazy: numba, scipy

    suffix = Path(a.out).suffix.lower()
    cspace = getattr(a, "bt_cspace", False)
    if cspace and suffix != ".bt":
        raise PlannerError(f"argument --bt-cspace: writes a .bt, not {a.out}")
    if suffix == ".bt":  # refused before the (long) build when the file cannot be written
        if cspace:
            check_cubic_name(a.generator if a.generator is not None else a.lattice, a.map)
        elif is_world_file(a.map):
            raise PlannerError(f"{a.map}: a saved world keeps no obstacles; write the .bt "
                               f"from the map itself, or give --bt-cspace for its blocked "
                               f"cells")
    w, label = build(a)
    if suffix == ".npz":
        save_world(w, a.out)
    elif suffix == ".bt" and not cspace:
        got = write_octomap(a.out, w)
        print(f"{a.out}: OctoMap of the obstacles of {label}, {got.occupied} occupied and "
              f"{got.free} free voxels of {got.resolution:g} m (unknown left out; the "
              f"radius is not applied: --bt-cspace writes the blocked cells)")
        return 0
    else:
        write_world_cells(a.out, w, cspace=cspace)
    print(f"{a.out}: {label} world, {w.n_blocked} blocked and {w.n_unknown} unknown "
          f"cells, radius {w.radius:g} m, unknown space {w.unknown_policy}, built in "
          f"{w.build_seconds:.2f} s")
    return 0


def view(a: argparse.Namespace) -> int:
    """Write one self-contained .html view of the world and the given path files."""
    from planner.view import read_path_file, write_view  # lazy: numba, scipy

    paths = dict(read_path_file(p) for p in a.path)  # bad files refused before the build
    w, label = build(a)
    write_view(a.out, w, paths, max_cells=a.max_cells)
    print(f"{a.out}: {label} world, {w.n_blocked} blocked and {w.n_unknown} unknown "
          f"cells, {len(paths)} path(s)")
    return 0
