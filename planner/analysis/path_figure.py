"""The figure of ``planner plan --plot`` and ``planner compare --plot``: paths over the cells.

A 3D panel (3D maps only) with sub-sampled blocked cells near the paths, and a top view of
the share of blocked cells in each x-y bin over the paths' heights, with a colour bar.
The share is the blocked cells over *all* lattice cells whose centres fall in the bin and
the height slab, so a non-cubic lattice (whose centres fall unevenly into square bins)
does not draw a checkerboard. Unknown space (cells meeting it) is drawn in its own colour
on both panels. The start is a ring drawn over the goal's star, so both show when they
share x, y.
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


def plot_paths(path: str, world, results: dict, *, title: str | None = None,
               max_cells: int = 4000) -> None:
    """Write the figure (module docstring) of ``results`` (label -> PlanResult) to ``path``
    (PNG, PDF or SVG by the suffix). ``title``: what is plotted, e.g. which query."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # drawn in the world's local frame, where its cells are
    paths = {k: world.to_local(r.path) for k, r in results.items() if r.found and len(r.path)}
    if not paths:
        raise PlanError("nothing to plot: no path was found")
    allp = np.concatenate(list(paths.values()))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    margin = 0.15 * (hi - lo).max() + 4 * world.lattice.covering_radius
    lat = world.lattice
    centres = world.blocked_centres()
    unknown = lat.to_world(world.unknown) if world.n_unknown else np.zeros((0, 3))
    if len(unknown) and len(centres):  # blocked by unknown space: drawn as unknown
        centres = centres[~world.is_unknown(world.blocked)]

    def near(c):
        return c[np.all((c >= lo - margin) & (c <= hi + margin), axis=1)]

    cells, unk = near(centres), near(unknown)
    three_d = world.dim == 3
    fig = plt.figure(figsize=(13, 6) if three_d else (8, 6.5))
    ax2 = fig.add_subplot(1, 2, 2) if three_d else fig.add_subplot(1, 1, 1)
    rng = np.random.default_rng(0)
    if three_d:
        ax3 = fig.add_subplot(1, 2, 1, projection="3d")
        for c, colour, cmap, name in ((cells, None, "Greys", "blocked cells"),
                                      (unk, _UNKNOWN, None, "unknown cells")):
            if len(c) > max_cells:
                c = c[rng.choice(len(c), max_cells, replace=False)]
            if len(c):
                ax3.scatter(*c.T, s=2, c=colour if colour else c[:, 2], cmap=cmap,
                            alpha=0.25, depthshade=False, label=name)
    step = 2 * lat.packing_radius
    xe = np.arange(lo[0] - margin, hi[0] + margin + step, step)
    ye = np.arange(lo[1] - margin, hi[1] + margin + step, step)
    # a 2D map: only the plane z = 0 of the prism lattice
    z0, z1 = (lo[2] - 0.3, hi[2] + 0.3) if three_d else (-0.25 * step, 0.25 * step)
    extent = (xe[0], xe[-1], ye[0], ye[-1])
    in_slab = cells[(cells[:, 2] >= z0) & (cells[:, 2] <= z1)]
    im = ax2.imshow(_share(in_slab, lat, xe, ye, z0, z1).T, origin="lower", cmap="Greys",
                    extent=extent, vmin=0, vmax=1, interpolation="nearest")
    fig.colorbar(im, ax=ax2, fraction=0.04, pad=0.02, shrink=0.8 if three_d else 0.6,
                 label="share of blocked cells" + (" over the path's heights" if three_d
                                                   else ""))
    u_slab = unk[(unk[:, 2] >= z0) & (unk[:, 2] <= z1)]
    if len(u_slab):
        u = _share(u_slab, lat, xe, ye, z0, z1).T
        ax2.imshow(np.ma.masked_where(u <= 0, u), origin="lower", extent=extent, vmin=0,
                   vmax=1, cmap=matplotlib.colors.ListedColormap([_UNKNOWN]), alpha=0.45,
                   interpolation="nearest")
        ax2.plot([], [], "s", color=_UNKNOWN, alpha=0.6, label="unknown space")
    for label, p in paths.items():
        r = results[label]
        text = f"{label}: {r.length:.2f} m, {r.cell_checks:,} checks"
        colour = LATTICE_COLORS.get(label)  # None: matplotlib's next colour
        if three_d:
            ax3.plot(*p.T, lw=2, label=text, color=colour)
        ax2.plot(p[:, 0], p[:, 1], lw=2, label=text, color=colour)
    first = next(iter(paths.values()))
    axes = [(ax2, 2)] + ([(ax3, 3)] if three_d else [])
    for ax, d in axes:  # the goal first, then the start as a ring over it
        ax.scatter(*first[-1][:d, None], marker="*", s=140, c="red", label="goal", zorder=5)
        ax.scatter(*first[0][:d, None], marker="o", s=170, facecolors="none",
                   edgecolors="green", linewidths=2.2, label="start", zorder=6)
    ax2.set_xlabel("x (m)")
    ax2.set_ylabel("y (m)")
    ax2.set_aspect("equal")
    ax2.set_title("top-down view" + (" (the path's heights)" if three_d else ""), fontsize=10)
    ax2.legend(fontsize=8, loc="best")
    name = Path(str(getattr(world, "source", "") or "")).name
    head = title or name
    if three_d:
        ax3.set_xlabel("x (m)")
        ax3.set_ylabel("y (m)")
        ax3.set_zlabel("z (m)")
        ax3.set_title("paths in 3D")
    fig.suptitle(head, fontsize=11)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=Path(path).suffix.lstrip(".") or "png",
                    bbox_inches="tight")
    plt.close(fig)
