"""The figure of ``planner plan --plot`` and ``planner compare --plot``: paths over the cells.

Per query, a 3D panel (3D maps only) and a top view:

* the 3D panel draws the *surface* of the blocked space near the paths (blocked cells with
  a free face neighbour, within a band around the paths), coloured by height, with equal
  axis scales, so walls read as walls beside the path rather than a box of dots;
* the top view draws, per pixel, the share of the paths' heights at which that point lies
  in a blocked cell (sampled at several heights through the slab, each point looked up in
  its own lattice cell): the cells' true footprints, so hex and FCC walls are solid, not
  dithered. Unknown space (cells meeting it) gets its own colour on both panels.

The start is a ring drawn over the goal's star, so both show when they share x, y.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.analysis.style import LATTICE_COLORS
from planner.errors import PlanError
from planner.fsutil import atomic_path

__all__ = ["plot_paths"]

_UNKNOWN = "#e08a1e"
_MAX_LATTICE_CELLS = 4_000_000  # beyond: the expected count per bin stands in
_PIXELS = 700  # top view: about this many pixels along its longer side
_HEIGHTS = 9  # top view: heights sampled through the paths' slab


def _cells_in_box(lattice, lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    """(N, 3) centres (m) of the lattice cells inside the box [lo, hi]; None when too many."""
    g = np.asarray(lattice.generator, dtype=float)
    corners = np.array([[(lo, hi)[b][a] for a, b in enumerate(bits)]
                        for bits in np.ndindex(2, 2, 2)])
    k = np.linalg.solve(g, corners.T).T
    kmin, kmax = np.floor(k.min(axis=0)).astype(int), np.ceil(k.max(axis=0)).astype(int)
    if np.prod(kmax - kmin + 1, dtype=float) > _MAX_LATTICE_CELLS:
        return None
    axes = [np.arange(a, b + 1) for a, b in zip(kmin, kmax, strict=True)]
    idx = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    pts = idx @ g.T
    return pts[np.all((pts >= lo) & (pts <= hi), axis=1)]


def _share(cells: np.ndarray, lattice, xe, ye, z0: float, z1: float) -> np.ndarray:
    """(nx, ny) share of the slab's lattice cells in each bin that are in ``cells``."""
    hist, _, _ = np.histogram2d(cells[:, 0], cells[:, 1], bins=(xe, ye))
    every = _cells_in_box(lattice, np.array([xe[0], ye[0], z0]), np.array([xe[-1], ye[-1], z1]))
    if every is None:
        den = np.full_like(hist, (xe[1] - xe[0]) * (ye[1] - ye[0]) * (z1 - z0)
                           / lattice.cell_volume)
    else:
        den, _, _ = np.histogram2d(every[:, 0], every[:, 1], bins=(xe, ye))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, np.minimum(hist / den, 1.0), 0.0)


def _surface(world, near_paths: np.ndarray, band: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres (N, 3) of blocked cells with a free face neighbour within ``band`` (m) of the
    path points ``near_paths`` (P, 3), and (U, 3) of such cells meeting unknown space."""
    from scipy.spatial import cKDTree

    lat = world.lattice
    lo, hi = near_paths.min(axis=0) - band, near_paths.max(axis=0) + band
    cells = world.blocked
    if not len(cells):
        return np.zeros((0, 3)), np.zeros((0, 3))
    c = lat.to_world(cells)
    box = np.all((c >= lo) & (c <= hi), axis=1)
    cells, c = cells[box], c[box]
    if len(c):
        d, _ = cKDTree(near_paths).query(c, distance_upper_bound=band)
        cells, c = cells[np.isfinite(d)], c[np.isfinite(d)]
    nb = lat.neighbors("face")
    free = np.zeros(len(cells), dtype=bool)
    for off in nb:  # on the surface: some face neighbour is free
        free |= world.is_free(cells + off)
    cells, c = cells[free], c[free]
    unk = world.is_unknown(cells) if world.n_unknown and len(cells) else np.zeros(len(c), bool)
    return c[~unk], c[unk]


def _dense(p: np.ndarray, step: float) -> np.ndarray:
    """Points every ``step`` (m) along the polyline ``p`` (K, 3), ends included."""
    out = [p[:1]]
    for a, b in zip(p[:-1], p[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        out.append(a + np.linspace(0, 1, n + 1)[1:, None] * (b - a))
    return np.concatenate(out)


def _footprint(world, xe: np.ndarray, ye: np.ndarray, z0: float, z1: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """(ny, nx) share of the heights in [z0, z1] at which each pixel centre lies in a
    blocked cell, and the share in a cell meeting unknown space."""
    lat = world.lattice
    xc, yc = (xe[:-1] + xe[1:]) / 2, (ye[:-1] + ye[1:]) / 2
    zs = np.linspace(z0, z1, _HEIGHTS) if z1 > z0 else np.array([z0])
    blocked = np.zeros((len(yc), len(xc)))
    unknown = np.zeros_like(blocked)
    gx, gy = np.meshgrid(xc, yc)
    for z in zs:
        pts = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, z)])
        cells = lat.quantize(pts)
        blocked += (~world.is_free(cells)).reshape(gx.shape)
        if world.n_unknown:
            unknown += world.is_unknown(cells).reshape(gx.shape)
    return blocked / len(zs), unknown / len(zs)


def _set_equal_3d(ax, lo: np.ndarray, hi: np.ndarray) -> None:
    """Equal metres on the three axes (a wall 3 m tall looks 3 m tall)."""
    ext = np.maximum(hi - lo, 1e-9)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(np.maximum(ext, 0.08 * ext.max())))


def plot_paths(path: str, world, results, *, title: str | list[str] | None = None,
               max_cells: int = 6000, suptitle: str | None = None) -> None:
    """Write the figure (module docstring) of ``results`` to ``path`` (PNG, PDF or SVG by
    the suffix). ``results``: label -> PlanResult for one query, or a list of such dicts
    (one row of panels per query, titled by ``title`` when it is a list of titles, under
    ``suptitle``).
    ``max_cells``: most surface cells drawn per 3D panel (the nearest to the paths kept)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    queries = results if isinstance(results, list) else [results]
    titles = title if isinstance(title, list) else [None] * len(queries)
    # drawn in the world's local frame, where its cells are
    found = [{k: world.to_local(r.path) for k, r in q.items() if r.found and len(r.path)}
             for q in queries]
    if not any(found):
        raise PlanError("nothing to plot: no path was found")
    three_d = world.dim == 3
    rows = len(queries)
    fig = plt.figure(figsize=((14, 6 * rows) if three_d else (8, 6.5 * rows)))
    for row, (res, paths, sub) in enumerate(zip(queries, found, titles, strict=True)):
        if not paths:
            ax = fig.add_subplot(rows, 1, row + 1)
            ax.set_axis_off()
            ax.set_title(f"{sub or ''}: no path found", fontsize=10)
            continue
        _draw_query(fig, rows, row, world, res, paths, three_d, max_cells, sub, matplotlib)
    name = Path(str(getattr(world, "source", "") or "")).name
    head = suptitle or (title if isinstance(title, str) and title else name)
    fig.suptitle(head, fontsize=11)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=Path(path).suffix.lstrip(".") or "png",
                    bbox_inches="tight")
    plt.close(fig)


def _draw_query(fig, rows, row, world, results, paths, three_d, max_cells, sub, matplotlib):
    """One query's panels in row ``row`` of ``fig``."""
    lat = world.lattice
    allp = np.concatenate(list(paths.values()))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    margin = 0.15 * (hi - lo).max() + 4 * lat.covering_radius
    edge = lat.cell_volume ** (1 / 3)
    if three_d:
        ax3 = fig.add_subplot(rows, 2, 2 * row + 1, projection="3d", computed_zorder=False)
        band = max(4 * edge, world.radius + 3 * edge, 0.06 * float(np.linalg.norm(hi - lo)))
        dense = _dense(np.concatenate([_dense(p, edge) for p in paths.values()]), edge)
        surf, unk = _surface(world, dense, band)
        if len(surf) > max_cells:  # keep the nearest to the paths
            from scipy.spatial import cKDTree

            d, _ = cKDTree(dense).query(surf)
            surf = surf[np.argsort(d, kind="stable")[:max_cells]]
        box_lo = np.minimum(lo - band, surf.min(axis=0) if len(surf) else lo)
        box_hi = np.maximum(hi + band, surf.max(axis=0) if len(surf) else hi)
        size = float(np.clip(20000 / max(len(surf), 1), 3, 30))
        if len(surf):
            ax3.scatter(*surf.T, s=size, c=surf[:, 2], cmap="viridis", alpha=0.55,
                        depthshade=True, linewidths=0, zorder=1,
                        label=f"obstacle surface within {band:.2g} m (by height)")
        if len(unk):
            ax3.scatter(*unk.T, s=size, c=_UNKNOWN, alpha=0.55, depthshade=True,
                        linewidths=0, zorder=1, label="unknown space")
        ax2 = fig.add_subplot(rows, 2, 2 * row + 2)
    else:
        ax2 = fig.add_subplot(rows, 1, row + 1)
    px = max((hi - lo)[:2].max() + 2 * margin, 1e-9) / _PIXELS
    px = min(px, edge / 2) if (hi - lo)[:2].max() + 2 * margin < _PIXELS * edge / 2 else px
    xe = np.arange(lo[0] - margin, hi[0] + margin + px, px)
    ye = np.arange(lo[1] - margin, hi[1] + margin + px, px)
    # a 2D map: only the plane z = 0 of the prism lattice
    z0, z1 = (lo[2], hi[2]) if three_d else (0.0, 0.0)
    extent = (xe[0], xe[-1], ye[0], ye[-1])
    blocked, unknown = _footprint(world, xe, ye, z0, z1)
    blocked = np.where(unknown > 0, np.maximum(blocked - unknown, 0), blocked)
    im = ax2.imshow(blocked, origin="lower", cmap="Greys", extent=extent, vmin=0, vmax=1,
                    interpolation="nearest")
    fig.colorbar(im, ax=ax2, fraction=0.04, pad=0.02, shrink=0.8 if three_d else 0.6,
                 label="blocked share of the path's heights" if three_d else "blocked")
    if unknown.any():
        ax2.imshow(np.ma.masked_where(unknown <= 0, unknown), origin="lower", extent=extent,
                   vmin=0, vmax=1, cmap=matplotlib.colors.ListedColormap([_UNKNOWN]),
                   alpha=0.45, interpolation="nearest")
        ax2.plot([], [], "s", color=_UNKNOWN, alpha=0.6, label="unknown space")
    for label, p in paths.items():
        r = results[label]
        text = f"{label}: {r.length:.2f} m, {r.cell_checks:,} checks"
        colour = LATTICE_COLORS.get(label)  # None: matplotlib's next colour
        if three_d:
            ax3.plot(*p.T, lw=2.5, label=text, color=colour, zorder=10)
        ax2.plot(p[:, 0], p[:, 1], lw=2, label=text, color=colour)
    first = next(iter(paths.values()))
    axes = [(ax2, 2)] + ([(ax3, 3)] if three_d else [])
    for ax, d in axes:  # the goal first, then the start as a ring over it
        ax.scatter(*first[-1][:d, None], marker="*", s=140, c="red", label="goal", zorder=11)
        ax.scatter(*first[0][:d, None], marker="o", s=170, facecolors="none",
                   edgecolors="green", linewidths=2.2, label="start", zorder=12)
    ax2.set_xlabel("x (m)")
    ax2.set_ylabel("y (m)")
    ax2.set_aspect("equal")
    heights = (f"z {z0:.2f}-{z1:.2f} m" if z1 > z0 else f"z {z0:.2f} m") if three_d else ""
    ax2.set_title((f"{sub}\n" if sub else "") + "top-down view, true cell footprints"
                  + (f" ({heights})" if heights else ""), fontsize=10)
    ax2.legend(fontsize=8, loc="best")
    if three_d:
        _set_equal_3d(ax3, box_lo, box_hi)
        ax3.view_init(elev=28, azim=-65)
        ax3.set_xlabel("x (m)")
        ax3.set_ylabel("y (m)")
        ax3.set_zlabel("z (m)", labelpad=-4)
        ax3.set_title("paths in 3D, between the obstacle surfaces near them", fontsize=10)
        ax3.legend(fontsize=7, loc="upper left")
