"""Trade-off figures of a benchmark: one point per lattice x neighbours x method x cell volume.

- ``pareto.png``: median cell checks per query (search + smoothing) against the median
  path length ratio (raw and smoothed panels), per map; the Pareto front (fewer checks
  *and* shorter) is outlined.
- ``success_vs_resolution.png``: success rate against cell volume, and against the
  lattice's covering radius (the comparison at equal covering radius: a lattice with a
  smaller covering radius at the same volume sits further left).
- ``time_vs_length.png``: median CPU time to the delivered path (search + smoothing)
  against median delivered length ratio.

Colours are the project's one colour per lattice; markers tell the method; filled markers
are the full neighbour set, hollow ones the face neighbours (and in
``success_vs_resolution.png`` line styles too). With a single cell volume per map the
success figure is one bar per configuration with its 95% Wilson interval and n instead of
curves over a one-point axis.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np

from planner.analysis.style import LATTICE_COLORS, OTHER_COLOR
from planner.bench.paired import query_key, wilson_interval
from planner.fsutil import atomic_path
from planner.lattice import Lattice

__all__ = ["operating_points", "pareto_front", "plot_tradeoffs"]

_MARKERS = {"astar": "o", "dijkstra": "s", "theta": "^", "lazy-theta": "D",
            "weighted-theta": "v"}
_STYLES = {"face": "--", "full": "-"}


def operating_points(rows: list[dict]) -> list[dict]:
    """One record per map x lattice x neighbours x method x cell volume (lattice methods).

    Needs rows with ``length_ratio`` / ``raw_length_ratio`` (:func:`summary.add_ratios`).
    Fields: success rate over all queries; medians of cell checks and CPU time
    (``seconds``) to the delivered path, raw and smoothed length ratio over the queries
    that *every* configuration of that map and cell volume solved (medians over each one's
    own solved queries would favour a configuration that fails the hard ones); the
    lattice's covering radius at that cell volume (m).
    """
    groups: dict = defaultdict(list)
    for r in rows:
        if not str(r["method"]).startswith("ompl:"):
            groups[(r["map"], r["lattice"], r["neighbors"], r["method"],
                    r["cell_volume"])].append(r)
    solved: dict = {}
    for (m, _, _, _, cv), rs in groups.items():
        keys = {query_key(r) for r in rs if r.get("found")}
        solved[(m, cv)] = keys if (m, cv) not in solved else solved[(m, cv)] & keys
    out = []
    for (m, lat, nb, meth, cv), rs in groups.items():
        ok = [r for r in rs if r.get("found") and query_key(r) in solved[(m, cv)]]

        def med(key, ok=ok):
            v = [r[key] for r in ok if r.get(key) is not None]
            return float(np.median(v)) if v else np.nan

        out.append({"map": m, "lattice": lat, "neighbors": nb, "method": meth,
                    "cell_volume": cv, "success": sum(bool(r.get("found")) for r in rs) / len(rs),
                    "common_queries": len(ok),
                    "covering_radius": Lattice.named(lat, cell_volume=cv).covering_radius,
                    "cell_checks": med("cell_checks"), "seconds": med("cpu_seconds"),
                    "raw_length_ratio": med("raw_length_ratio"),
                    "length_ratio": med("length_ratio")})
    return out


def pareto_front(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(N,) bool: points not dominated (no other point has x' <= x and y' <= y, one <).

    >>> pareto_front(np.array([1.0, 2.0, 1.5]), np.array([3.0, 1.0, 3.5])).tolist()
    [True, True, False]
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    keep = np.isfinite(x) & np.isfinite(y)
    front = keep.copy()
    for i in np.flatnonzero(keep):
        dom = keep & (x <= x[i]) & (y <= y[i]) & ((x < x[i]) | (y < y[i]))
        front[i] = not dom.any()
    return front


def _save(fig, path: Path) -> Path:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    return path


def _log_y(ax, y) -> None:
    """Log scale when there is something positive to show (no query solved by all: none)."""
    y = np.asarray(y, dtype=float)
    if np.any(np.isfinite(y) & (y > 0)):
        ax.set_yscale("log")


def _colour(lat: str) -> str:
    return LATTICE_COLORS.get(lat, OTHER_COLOR)


def _legend(ax, pts: list[dict], lines: bool = False) -> None:
    """Lattice colours, method markers and the neighbour sets as the figure draws them:
    hollow / filled markers, with their line styles when ``lines``."""
    from matplotlib.lines import Line2D

    lats = [lat for lat in LATTICE_COLORS if any(p["lattice"] == lat for p in pts)]
    meths = sorted({p["method"] for p in pts})
    nbs = sorted({p["neighbors"] for p in pts})
    h = [Line2D([], [], color=_colour(lat), marker="o", ls="", label=lat) for lat in lats]
    h += [Line2D([], [], color="black", markerfacecolor="white", marker=_MARKERS.get(m, "x"),
                 ls="", label=m) for m in meths]
    h += [Line2D([], [], color="black", marker="o", ls=_STYLES.get(n, ":") if lines else "",
                 markerfacecolor="white" if n == "face" else "black",
                 label=f"{n} nbrs") for n in nbs]
    ax.legend(handles=h, fontsize=7, loc="best")


def plot_tradeoffs(rows: list[dict], out_dir: Path) -> list[Path]:
    """Write the three trade-off figures; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pts = operating_points(rows)
    if not pts:
        return []
    maps = sorted({p["map"] for p in pts})
    files = []

    fig, axes = plt.subplots(len(maps), 2, figsize=(11, 4.2 * len(maps)), squeeze=False)
    for i, m in enumerate(maps):
        mp = [p for p in pts if p["map"] == m]
        for j, (key, name) in enumerate((("raw_length_ratio", "raw"),
                                         ("length_ratio", "smoothed"))):
            ax = axes[i, j]
            x = np.array([p[key] for p in mp])
            y = np.array([p["cell_checks"] for p in mp])
            front = pareto_front(x, y)
            for p, xi, yi, f in zip(mp, x, y, front, strict=True):
                c = _colour(p["lattice"])
                ax.scatter(xi, yi, facecolors=c if p["neighbors"] != "face" else "white",
                           marker=_MARKERS.get(p["method"], "x"), s=40, edgecolors=c,
                           linewidths=1.4, zorder=3)
                if f:  # a black ring around the front's points
                    ax.scatter(xi, yi, facecolors="none", edgecolors="black", s=160,
                               marker=_MARKERS.get(p["method"], "x"), linewidths=1.0,
                               zorder=4)
            order = np.argsort(x[front])
            ax.step(x[front][order], y[front][order], where="post", color="black", lw=0.8,
                    alpha=0.6, zorder=2)
            _log_y(ax, y)
            ax.set_xlabel(f"median {name} path length / best on the query")
            ax.set_ylabel("median cell checks to the delivered path")
            ax.set_title(f"{Path(m).name}: checks vs {name} length", fontsize=9)
            ax.grid(alpha=0.3)
            if i == 0 and j == 0:
                _legend(ax, mp)
    fig.suptitle("Ringed and joined: the Pareto front. Medians over the queries every "
                 "configuration of the map and cell volume solved.", fontsize=9)
    fig.tight_layout()
    files.append(_save(fig, out_dir / "pareto.png"))
    plt.close(fig)

    files.append(_success_figure(plt, pts, rows, maps, out_dir))

    fig, axes = plt.subplots(1, len(maps), figsize=(5.5 * len(maps), 4.2), squeeze=False)
    for i, m in enumerate(maps):
        ax = axes[0, i]
        mp = [p for p in pts if p["map"] == m]
        for p in mp:
            c = _colour(p["lattice"])
            ax.scatter(p["length_ratio"], p["seconds"], edgecolors=c, linewidths=1.4,
                       facecolors="white" if p["neighbors"] == "face" else c,
                       marker=_MARKERS.get(p["method"], "x"), s=36)
        _log_y(ax, [p["seconds"] for p in mp])
        ax.set_xlabel("median smoothed length / best on the query")
        ax.set_ylabel("median CPU time to the delivered path (s)")
        ax.set_title(f"{Path(m).name}: time vs length", fontsize=9)
        ax.grid(alpha=0.3)
        if i == 0:
            _legend(ax, mp)
    fig.tight_layout()
    files.append(_save(fig, out_dir / "time_vs_length.png"))
    plt.close(fig)
    return files


def _success_figure(plt, pts: list[dict], rows: list[dict], maps: list[str],
                    out_dir: Path) -> Path:
    """Success against cell volume and covering radius; one cell volume: bars with n."""
    from matplotlib.ticker import FixedLocator, NullLocator

    single = all(len({p["cell_volume"] for p in pts if p["map"] == m}) == 1 for m in maps)
    fig, axes = plt.subplots(len(maps), 1 if single else 2,
                             figsize=(11, (4.2 if single else 3.8) * len(maps)), squeeze=False)
    for i, m in enumerate(maps):
        mp = sorted((p for p in pts if p["map"] == m),
                    key=lambda p: (p["lattice"], p["neighbors"], p["method"], p["cell_volume"]))
        if single:
            ax = axes[i, 0]
            counts = []
            for p in mp:
                rs = [r for r in rows if r["map"] == m and r["lattice"] == p["lattice"]
                      and r["neighbors"] == p["neighbors"] and r["method"] == p["method"]
                      and r["cell_volume"] == p["cell_volume"]]
                counts.append((sum(bool(r.get("found")) for r in rs), len(rs)))
            x = np.arange(len(mp))
            rate = np.array([k / n for k, n in counts])
            lo, hi = np.array([wilson_interval(k, n) for k, n in counts]).T
            ax.bar(x, rate, color=[_colour(p["lattice"]) for p in mp], alpha=0.85)
            ax.errorbar(x, rate, yerr=np.clip([rate - lo, hi - rate], 0, None), fmt="none",
                        ecolor="black", capsize=3, lw=1)
            for xi, (k, n) in zip(x, counts, strict=True):
                ax.text(xi, 1.02, f"{k}/{n}", ha="center", va="bottom", fontsize=7)
            ax.set_xticks(x, [f"{p['lattice']} {p['neighbors']} {p['method']}" for p in mp],
                          rotation=45, ha="right", fontsize=8)
            ax.set_ylim(0, 1.12)
            ax.set_ylabel("success rate")
            ax.set_title(f"{Path(m).name}: success at the one cell volume "
                         f"{mp[0]['cell_volume']:g} m^3 (solved/n; 95% Wilson interval)",
                         fontsize=9)
            ax.grid(axis="y", alpha=0.3)
            continue
        curves: dict = defaultdict(list)
        for p in mp:
            curves[(p["lattice"], p["neighbors"], p["method"])].append(p)
        # a small horizontal offset per configuration, so equal rates do not hide markers
        shift = {k: 1.0 + 0.015 * (n - (len(curves) - 1) / 2) for n, k in enumerate(curves)}
        for j, (key, label) in enumerate((("cell_volume", "cell volume (m^3)"),
                                          ("covering_radius", "covering radius (m)"))):
            ax = axes[i, j]
            for (lat, nb, meth), cps in curves.items():
                cps = sorted(cps, key=lambda p: p[key])
                c = _colour(lat)
                ax.plot([p[key] * shift[(lat, nb, meth)] for p in cps],
                        [p["success"] for p in cps], color=c, ls=_STYLES.get(nb, ":"),
                        marker=_MARKERS.get(meth, "x"), markeredgecolor=c,
                        markerfacecolor="white" if nb == "face" else c, alpha=0.85)
            ax.set_xscale("log")
            ticks = sorted({p[key] for p in mp})
            ax.xaxis.set_major_locator(FixedLocator(ticks))
            ax.xaxis.set_minor_locator(NullLocator())
            ax.set_xticklabels([f"{t:.3g}" for t in ticks], fontsize=8)
            ax.set_ylim(-0.03, 1.03)
            ax.set_xlabel(label)
            ax.set_ylabel("success rate")
            ax.set_title(f"{Path(m).name}: success vs {label.split(' (')[0]}", fontsize=9)
            ax.grid(alpha=0.3)
            if i == 0 and j == 0:
                _legend(ax, mp, lines=True)
    fig.tight_layout()
    path = _save(fig, out_dir / "success_vs_resolution.png")
    plt.close(fig)
    return path
