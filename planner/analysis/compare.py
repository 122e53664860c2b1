"""The cross-lattice comparison (``planner compare``) and its path figure."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from planner import search
from planner.analysis.path_figure import plot_paths as draw
from planner.analysis.tables import format_table
from planner.errors import MapError, PlanError
from planner.io import load_scenarios
from planner.lattice import NAMED_LATTICES
from planner.lattice.paper import NAMED_LATTICES_2D
from planner.maps import resolve
from planner.path import path_length, read_record
from planner.planning import plan
from planner.progress import Progress
from planner.search import warm_up
from planner.view import write_view
from planner.world.build import as_obstacles, build_world, sidecar
from planner.world.caveats import world_warnings

__all__ = ["compare", "format_rows", "plot_paths"]


def compare(
    map_path: str,
    *,
    lattices: list | None = None,
    cell_volume: float | None = None,
    radius: float | None = None,
    bounds=None,
    start=None,
    goal=None,
    method: str = "astar",
    neighbors: str = "full",
    plot: str | None = None,
    plot_query: int | None = None,
    progress: bool = True,
    format: str | None = None,
    max_expansions: int | None = None,
    unknown: str | None = None,
    view: str | None = None,
    source=None,
) -> list[dict]:
    """Plan the same queries on every lattice and return one summary row per lattice.

    ``lattices`` holds names or :class:`~planner.lattice.Lattice` instances (a custom
    generator, scaled to the common cell volume when one is given or suggested by the map);
    None: every named lattice of the map's dimension (square and hex2d on a 2D map).

    Queries are ``start``/``goal`` when given, else the map's default queries (bundled
    maps' JSON sidecar). Radius and the rest default as in :func:`planner.build_world`; the
    cell volume, common to every lattice, to the sidecar's suggestion.
    ``max_expansions`` bounds each search (None: the memory budget's default).
    ``unknown`` is the unknown-space policy of :func:`planner.build_world` (None: the map's
    default); each row reports the unknown cells its paths cross.
    ``plot`` / ``view``: a figure / an interactive 3D page (:mod:`planner.view`) of every
    lattice's path of the first query over the last lattice's cells.
    ``progress``: one line on stderr with the plans done of lattices x queries and an ETA
    (:class:`planner.progress.Progress`).
    ``source``: the map already read (:class:`~planner.io.Obstacles`, e.g. a bag read with
    its topic and frame), built instead of reading ``map_path`` again; ``map_path`` still
    names the map's sidecar and default queries.
    """
    if not resolve(map_path).exists():
        raise MapError(f"{map_path}: no such file or bundled map")
    if lattices is None:  # every named lattice of the map's dimension
        dim = (source if source is not None else as_obstacles(resolve(map_path), format)).dim
        lattices = list(NAMED_LATTICES_2D if dim == 2 else NAMED_LATTICES)
    side = sidecar(resolve(map_path))
    if cell_volume is None:  # one cell volume for every lattice, custom generators too
        cell_volume = side.get("cell_volume")
    if start is not None and goal is not None:
        queries = [(np.asarray(start), np.asarray(goal))]
    elif start is not None or goal is not None:
        raise PlanError("give both --start and --goal, or neither to use the map's queries")
    else:
        queries = [(np.asarray(q["start"]), np.asarray(q["goal"])) for q in side.get("queries", [])]
        queries = queries or _scenario_queries(map_path)
        if not queries:
            raise PlanError(f"{map_path}: no default queries; pass --start and --goal")
    rows, results = [], {}
    bar = Progress(len(lattices) * len(queries), "plans", enabled=progress)
    with bar:
        for lat in lattices:
            name = lat if isinstance(lat, str) else (lat.name or "custom")
            bar.label = name
            bar.step(0)  # shows the lattice while its world is built
            t0 = time.perf_counter()
            world = build_world(map_path if source is None else source, lat,
                                cell_volume=cell_volume, radius=radius, bounds=bounds,
                                format=format, unknown=unknown)
            build = time.perf_counter() - t0
            compile_s = warm_up()  # JIT / cache load of the search kernels: not search time
            per = []
            for s, g in queries:
                per.append(plan(world, s, g, method=method, neighbors=neighbors,
                                max_expansions=max_expansions))
                bar.step()
            rows.append(_row(world, name, per, build, compile_s, method, neighbors))
            results[name] = per
    if plot:
        shown = _plotted(plot_query, len(queries))
        cells = f"; cells of {name}" if len(results) > 1 else ""
        plot_paths(plot, world, [{k: per[q] for k, per in results.items()} for q in shown],
                   title=[f"query {q + 1} of {len(queries)}: {_xyz(queries[q][0])} -> "
                          f"{_xyz(queries[q][1])}" for q in shown],
                   suptitle=f"{Path(map_path).name}: "
                            + _which(shown, len(queries)) + cells)
    if view:
        q = (plot_query or 1) - 1
        s, g = queries[q]
        write_view(view, world, {k: per[q].path for k, per in results.items()
                                 if per[q].found}, start=s, goal=g,
                   title=f"{Path(map_path).name}: query {q + 1} of {len(queries)}, cells "
                         f"of the {name} lattice")
    return rows


#: most queries drawn in one ``compare --plot`` figure (one row of panels each)
PLOT_QUERIES = 4


def _plotted(plot_query: int | None, n: int) -> list[int]:
    """0-based queries a figure shows: the one asked for, else the first
    :data:`PLOT_QUERIES`."""
    if plot_query is None:
        return list(range(min(n, PLOT_QUERIES)))
    if not 1 <= plot_query <= n:
        raise PlanError(f"--plot-query {plot_query}: there are {n} queries (1..{n})")
    return [plot_query - 1]


def _which(shown: list[int], n: int) -> str:
    """What a figure's queries are, in words (it says when some are left out)."""
    if len(shown) == 1:
        return f"query {shown[0] + 1} of {n}"
    if len(shown) == n:
        return f"all {n} queries"
    return (f"queries 1-{len(shown)} of {n} (--plot-query N draws another)")


def _row(world, name: str, per: list, build: float, compile_s: float, method: str,
         neighbors: str) -> dict:
    """One lattice's summary row over its per-query results ``per``."""
    found = [r for r in per if r.found]
    smoothed = [_smoothed_length(world, r) for r in found]
    return {
        "lattice": name,
        "cell_volume": world.lattice.cell_volume,
        "neighbors": neighbors,
        "method": method,
        "queries": len(per),
        "found": len(found) == len(per),
        "n_found": len(found),
        "length": float(sum(r.length for r in found)) if found else math.inf,
        "length_smoothed": float(sum(smoothed)) if found else math.inf,
        "cell_checks": int(sum(r.cell_checks for r in per)),
        "expansions": int(sum(r.expansions for r in per)),
        "seconds": float(sum(r.seconds for r in per)),
        "build_seconds": build,
        "compile_seconds": compile_s,
        "blocked_cells": int(world.n_blocked),
        "unknown_cells": int(sum(r.unknown_cells or 0 for r in found)),
        "read": read_record(world),
        "warnings": world_warnings(world),
    }


SCENARIO_QUERIES = 5  # of a MovingAI map's .3dscen file: its first ones, as in the file


def _scenario_queries(map_path: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """The first :data:`SCENARIO_QUERIES` queries of the ``MAP.3dscen`` file beside a
    MovingAI map (voxel centres, m); none without that file. A corrupt one is a MapError
    naming it, not a silent "no queries"."""
    scen = Path(str(map_path) + ".3dscen")
    if not scen.is_file():
        return []
    sc = load_scenarios(scen)
    k = min(len(sc), SCENARIO_QUERIES)
    return [(sc.starts[i].astype(float), sc.goals[i].astype(float)) for i in range(k)]


def _smoothed_length(world, res) -> float:
    """Length (m) after line-of-sight shortcutting (A*/Dijkstra cell paths); any-angle and
    OMPL paths are their own smoothed path."""
    if res.method not in ("astar", "dijkstra") or len(res.cells) < 3:
        return float(res.length)
    cells = search.shortcut(world, res.cells)
    pts = np.concatenate([res.path[:1], world.to_map(world.lattice.to_world(cells)),
                          res.path[-1:]])
    return float(path_length(pts))


def format_rows(rows: list[dict], markdown: bool = False) -> str:
    """Table of :func:`compare` rows, with ratios to cubic (square on a 2D map) where
    present, else to the first row.

    Raw length: the path as searched; smoothed: after line-of-sight shortcutting (what
    ``planner plan --shortcut`` returns).  Both are sums over the queries solved.
    """
    # the reference: the cubic lattice, on a 2D map the square one, else the first row
    base = next((r for ref in ("cubic", "square") for r in rows if r["lattice"] == ref),
                rows[0] if rows else None)
    vs = f"vs {base['lattice']}" if base else "vs cubic"
    head = ["lattice", "found", "raw length m", vs, "smoothed length m", vs,
            "cell checks", vs,
            "expansions", "search s", "build s", "compile s", "blocked cells"]
    keys = [f"c{i}" for i in range(len(head))]  # titles repeat ("vs cubic")
    out = []
    for r in rows:
        def ratio(key, r=r):
            b, v = base.get(key, math.nan), r.get(key, math.nan)
            return f"{v / b:.3f}" if b and math.isfinite(b) and math.isfinite(v) else "-"

        out.append(dict(zip(keys, [
            r["lattice"], f"{r['n_found']}/{r['queries']}", f"{r['length']:.3f}",
            ratio("length"), f"{r.get('length_smoothed', math.nan):.3f}",
            ratio("length_smoothed"), f"{r['cell_checks']:,}", ratio("cell_checks"),
            f"{r['expansions']:,}", f"{r['seconds']:.3f}", f"{r['build_seconds']:.2f}",
            f"{r.get('compile_seconds', 0.0):.2f}", f"{r['blocked_cells']:,}",
        ], strict=True)))
    text = format_table(out, keys, headers=head, markdown=markdown)
    if rows:
        r0 = rows[0]
        text += (f"\n(sums over {r0['queries']} queries; {r0['method']}, "
                 f"{r0['neighbors']} neighbours; lengths in metres; compile s: the search "
                 f"kernels' first-use compilation or cache load, never in search s)")
        text += "".join(f"\nWARNING: {w}" for w in r0.get("warnings", []))
    return text


def plot_paths(path: str, world, results, max_cells: int = 6000,
               title: str | list[str] | None = None, suptitle: str | None = None) -> None:
    """Figure of paths over the cells: see :func:`planner.analysis.path_figure.plot_paths`."""
    draw(path, world, results, title=title, max_cells=max_cells, suptitle=suptitle)


def _xyz(p) -> str:
    return "(" + ", ".join(f"{v:.2f}" for v in np.asarray(p, dtype=float)) + ")"
