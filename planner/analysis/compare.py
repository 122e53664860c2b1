"""The cross-lattice comparison (``planner compare``), path files and path figures."""

from __future__ import annotations

import csv
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from planner.analysis.style import LATTICE_COLORS
from planner.analysis.tables import format_table
from planner.errors import MapError, PlanError
from planner.fsutil import atomic_path
from planner.maps import read_sidecar

__all__ = ["compare", "describe", "format_rows", "map_defaults", "plot_paths", "write_path"]


def describe(res) -> str:
    """One human-readable paragraph about a PlanResult."""
    ompl = res.method.startswith("ompl:")
    head = f"{res.lattice} (cell volume {res.cell_volume:.6g} m^3), {res.method}" + (
        " (continuous, validated on this lattice's world)" if ompl else f", {res.neighbors}")
    if not res.found:
        return f"{head}: no path ({res.reason}); {res.cell_checks} cell checks"
    work = "" if ompl else f", {res.expansions} expansions"
    note = f"; {res.reason}" if res.reason else ""
    return (
        f"{head}: length {res.length:.3f} m, {len(res.path)} waypoints, "
        f"{res.cell_checks} cell checks{work}, "
        f"{res.seconds * 1e3:.1f} ms search (+{res.build_seconds:.2f} s map build){note}"
    )


def write_path(path: str, res) -> None:
    """Write the path as CSV (x,y,z per waypoint) or JSON (the whole result), atomically."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".json"):
        raise PlanError(f"{path}: unknown output format {suffix!r}; use .csv or .json")
    with atomic_path(path) as tmp:
        if suffix == ".json":
            tmp.write_text(json.dumps(res.to_dict(), indent=1))
        else:
            with open(tmp, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(["x", "y", "z"])
                w.writerows(np.round(res.path, 6).tolist())


def map_defaults(map_path: str, radius: float | None = None,
                 cell_volume: float | None = None) -> tuple[float, float | None]:
    """Robot radius and cell volume for a map: the given values, else the map's sidecar.

    ``plan`` and ``compare`` share these defaults.  A map without a suggested radius needs
    an explicit one (a silent radius 0 would plan paths that graze obstacles).

    Returns
    -------
    radius : float
        Metres.
    cell_volume : float or None
        m^3; ``None`` lets :func:`planner.build_world` pick the map's native resolution.

    Raises
    ------
    PlanError
        No radius given and none suggested by the map.

    Examples
    --------
    >>> from planner.maps import resolve
    >>> map_defaults(str(resolve("office")))
    (0.25, 0.002)
    >>> map_defaults(str(resolve("office")), radius=0.1, cell_volume=0.01)
    (0.1, 0.01)
    """
    side = read_sidecar(map_path)
    if radius is None:
        if not Path(map_path).exists():
            raise MapError(f"{map_path}: no such file or bundled map")
        if side.get("robot_radius") is None:
            raise PlanError(f"{map_path}: the map suggests no robot radius; pass --radius "
                            "(metres, 0 for a point robot)")
        radius = float(side["robot_radius"])
    if cell_volume is None and side.get("cell_volume") is not None:
        cell_volume = float(side["cell_volume"])
    return float(radius), cell_volume


def compare(
    map_path: str,
    *,
    lattices: list,
    cell_volume: float | None = None,
    radius: float | None = None,
    bounds=None,
    start=None,
    goal=None,
    method: str = "astar",
    neighbors: str = "full",
    plot: str | None = None,
    progress: bool = True,
    format: str | None = None,
    max_expansions: int | None = None,
    unknown: str | None = None,
) -> list[dict]:
    """Plan the same queries on every lattice and return one summary row per lattice.

    ``lattices`` holds names or :class:`~planner.lattice.Lattice` instances (a custom
    generator, scaled to the common cell volume when one is given or suggested by the map).

    Queries are ``start``/``goal`` when given, else the map's default queries (bundled
    maps' JSON sidecar). Radius and cell volume default to the sidecar's suggestions.
    ``max_expansions`` bounds each search (None: the memory budget's default).
    ``unknown`` is the unknown-space policy of :func:`planner.build_world` (None: the map's
    default); each row reports the unknown cells its paths cross.
    """
    from planner import api

    side = read_sidecar(map_path)
    if start is not None and goal is not None:
        queries = [(np.asarray(start), np.asarray(goal))]
    elif start is not None or goal is not None:
        raise PlanError("give both --start and --goal, or neither to use the map's queries")
    else:
        queries = [(np.asarray(q["start"]), np.asarray(q["goal"])) for q in side.get("queries", [])]
        queries = queries or _scenario_queries(map_path)
        if not queries:
            raise PlanError(f"{map_path}: no default queries; pass --start and --goal")
    radius, cell_volume = map_defaults(map_path, radius, cell_volume)
    rows, results = [], {}
    for lat in lattices:
        name = lat if isinstance(lat, str) else (lat.name or "custom")
        t0 = time.perf_counter()
        world = api.build_world(map_path, lat, cell_volume=cell_volume, radius=radius,
                                bounds=bounds, format=format, unknown=unknown)
        build = time.perf_counter() - t0
        from planner.search import warm_up

        compile_s = warm_up()  # JIT / cache load of the search kernels: not search time
        per = []
        try:
            for i, (s, g) in enumerate(queries):
                if progress:
                    print(f"\r{name}: query {i + 1}/{len(queries)}", end="", file=sys.stderr,
                          flush=True)
                per.append(api.plan(world, s, g, method=method, neighbors=neighbors,
                                    max_expansions=max_expansions))
        finally:  # clear the progress line, also before an error message
            if progress:
                print("\r" + " " * 40 + "\r", end="", file=sys.stderr, flush=True)
        results[name] = per[0]
        found = [r for r in per if r.found]
        smoothed = [_smoothed_length(world, r) for r in found]
        rows.append({
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
        })
    if plot:
        plot_paths(plot, world, results)
    return rows


SCENARIO_QUERIES = 5  # of a MovingAI map's .3dscen file: its first ones, as in the file


def _scenario_queries(map_path: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """The first :data:`SCENARIO_QUERIES` queries of the ``MAP.3dscen`` file beside a
    MovingAI map (voxel centres, m); none without that file. A corrupt one is a MapError
    naming it, not a silent "no queries"."""
    scen = Path(str(map_path) + ".3dscen")
    if not scen.is_file():
        return []
    from planner.io import load_scenarios

    sc = load_scenarios(scen)
    k = min(len(sc), SCENARIO_QUERIES)
    return [(sc.starts[i].astype(float), sc.goals[i].astype(float)) for i in range(k)]


def _smoothed_length(world, res) -> float:
    """Length (m) after line-of-sight shortcutting (A*/Dijkstra cell paths); any-angle and
    OMPL paths are their own smoothed path."""
    from planner import search
    from planner.paths import path_length

    if res.method not in ("astar", "dijkstra") or len(res.cells) < 3:
        return float(res.length)
    cells = search.shortcut(world, res.cells)
    pts = np.concatenate([res.path[:1], world.lattice.to_world(cells), res.path[-1:]])
    return float(path_length(pts))


def format_rows(rows: list[dict], markdown: bool = False) -> str:
    """Table of :func:`compare` rows, with ratios to cubic where present.

    Raw length: the path as searched; smoothed: after line-of-sight shortcutting (what
    ``planner plan --shortcut`` returns).  Both are sums over the queries solved.
    """
    base = next((r for r in rows if r["lattice"] == "cubic"), rows[0] if rows else None)
    head = ["lattice", "found", "raw length m", "vs cubic", "smoothed length m", "vs cubic",
            "cell checks", "vs cubic",
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
    return text


def plot_paths(path: str, world, results: dict, max_cells: int = 4000) -> None:
    """Figure of paths over the occupied cells near them: a 3D view and a top-down view.

    Parameters
    ----------
    path : str
        Output PNG file.
    world : World
        Its blocked cells are drawn (sub-sampled to ``max_cells`` near the paths).
    results : dict of str -> PlanResult
        Paths to draw, by label.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = {k: r.path for k, r in results.items() if r.found and len(r.path)}
    if not paths:
        raise PlanError("nothing to plot: no path was found")
    allp = np.concatenate(list(paths.values()))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    margin = 0.15 * (hi - lo).max() + 4 * world.lattice.covering_radius
    centres = world.blocked_centres()
    near = np.all((centres >= lo - margin) & (centres <= hi + margin), axis=1)
    cells = centres[near]
    if len(cells) > max_cells:
        cells = cells[np.random.default_rng(0).choice(len(cells), max_cells, replace=False)]
    fig = plt.figure(figsize=(13, 6))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    ax3.scatter(*cells.T, s=2, c=cells[:, 2], cmap="Greys", alpha=0.25, depthshade=False)
    # Top-down: the share of blocked cells in each x-y bin over the paths' height range, so
    # walls read as dark lines and open floor as white (a scatter of all floors is noise).
    slab = centres[near & (centres[:, 2] >= lo[2] - 0.3) & (centres[:, 2] <= hi[2] + 0.3)]
    step = 2 * world.lattice.packing_radius
    xe = np.arange(lo[0] - margin, hi[0] + margin + step, step)
    ye = np.arange(lo[1] - margin, hi[1] + margin + step, step)
    layers = max(1.0, (hi[2] - lo[2] + 0.6) / step)
    if len(slab):
        hist, _, _ = np.histogram2d(slab[:, 0], slab[:, 1], bins=(xe, ye))
        ax2.imshow(np.minimum(hist.T / layers, 1.0), origin="lower", cmap="Greys",
                   extent=(xe[0], xe[-1], ye[0], ye[-1]), vmin=0, vmax=1, alpha=0.8,
                   interpolation="nearest")
    for label, p in paths.items():
        r = results[label]
        text = f"{label}: {r.length:.2f} m, {r.cell_checks:,} checks"
        colour = LATTICE_COLORS.get(label)  # None: matplotlib's next colour
        ax3.plot(*p.T, lw=2, label=text, color=colour)
        ax2.plot(p[:, 0], p[:, 1], lw=2, label=text, color=colour)
    first = next(iter(paths.values()))
    for ax, pts in ((ax3, (first[0], first[-1])), (ax2, (first[0][:2], first[-1][:2]))):
        ax.scatter(*np.array(pts[:1]).T, marker="o", s=60, c="green", label="start", zorder=5)
        ax.scatter(*np.array(pts[1:]).T, marker="*", s=120, c="red", label="goal", zorder=5)
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("z (m)")
    ax2.set_xlabel("x (m)")
    ax2.set_ylabel("y (m)")
    ax2.set_aspect("equal")
    ax2.set_title("top-down view (grey: share of blocked cells over the path's heights)",
                  fontsize=10)
    ax3.set_title(f"{Path(str(getattr(world, 'source', ''))).name}: paths in 3D")
    ax2.legend(fontsize=8, loc="best")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=Path(path).suffix.lstrip(".") or "png",
                    bbox_inches="tight")
    plt.close(fig)
