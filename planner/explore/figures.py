"""Pictures of an exploration run (:class:`planner.explore.ExploreResult`): the summary
figure (PNG) and the animated GIF, one frame per replan.

Both show a top view sliced at the robot's height (obstacle points within 0.5 m of the
median trajectory height). The animation adds what the robot knew at each replan: the
space its horizontal sensor rays had swept (the *observed* area, white; never observed:
grey), the obstacles seen so far (black; the true ones not yet seen faint), the trajectory
so far, the path it was about to follow (dotted magenta where it leaves the slice, e.g.
over a wall through unknown space, with its height range in the title), the goal and the
robot's disc. On the summary's log axes a replan with zero cell checks is a hollow triangle
at a floor below every other value, counted in the legend.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.errors import PlanError
from planner.fsutil import atomic_path

__all__ = ["animate_gif", "floor_of", "frame_replans", "split_at_slice", "summary_png"]

_SLICE = 0.5  # m either side of the median robot height
_LABEL = {"astar": "A* when the path is hit", "dstar": "D* Lite (repair + search)"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _band(res) -> np.ndarray:
    """(N,) bool: obstacle points in the slice at the robot's height."""
    return np.abs(res.points[:, 2] - np.median(res.trajectory[:, 2])) <= _SLICE


def summary_png(res, path: str | Path) -> Path:
    """Top view with the true and the seen obstacles and the trajectory; per-replan cell
    checks and times of the replanner and A*. Written atomically; returns the path."""
    plt = _pyplot()
    fig, (ax, ac, at) = plt.subplots(1, 3, figsize=(16, 5),
                                     gridspec_kw={"width_ratios": [1.6, 1, 1]})
    band = _band(res)
    pts = res.points[band]
    ax.scatter(pts[:, 0], pts[:, 1], s=0.3, c="0.8", label="true obstacles (slice)")
    sp = res.points[band & res.seen]
    ax.scatter(sp[:, 0], sp[:, 1], s=0.5, c="k", label="seen")
    ax.plot(res.trajectory[:, 0], res.trajectory[:, 1], "-", c="tab:red", lw=1.5,
            label=f"robot, {res.distance:.1f} m")
    ax.plot(*res.start[:2], "o", c="tab:green", label="start")
    ax.plot(*res.goal[:2], "*", c="tab:blue", ms=12, label="goal")
    ax.set_aspect("equal")
    ax.set_title(f"{res.lattice}: {res.status}, {res.replans} replans, "
                 f"{res.mismatches} mismatches, {res.contacts} contacts", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.08), ncol=3,
              frameon=False)
    for a, (d, s, what) in ((ac, (res.replan_checks, res.astar_checks, "cell checks")),
                            (at, (res.replan_seconds, res.astar_seconds, "seconds"))):
        _log_dots(a, [(s, "0.5", "A* from scratch"),
                      (d, "tab:red", _LABEL.get(res.replanner, res.replanner))], what)
    fig.tight_layout()
    out = Path(path)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return out


def floor_of(values: list[np.ndarray]) -> float:
    """Where zeros go on a log axis: a third of the smallest positive value (1 if none)."""
    pos = np.concatenate([np.asarray(v, dtype=float) for v in values])
    pos = pos[pos > 0]
    return float(pos.min()) / 3 if len(pos) else 1.0


def _log_dots(a, series: list, what: str) -> None:
    """Per-replan values on a log axis; zeros (a kept replan checks nothing) are drawn as
    hollow triangles at a floor below every other value, counted in the legend, so no
    replan silently drops off the axis."""
    floor = floor_of([v for v, _, _ in series])
    for v, colour, label in series:
        v = np.asarray(v, dtype=float)
        i = np.arange(len(v))
        zero = v <= 0
        a.semilogy(i[~zero], v[~zero], ".", c=colour, label=label)
        if zero.any():
            a.semilogy(i[zero], np.full(zero.sum(), floor), "v", mfc="none", mec=colour,
                       ms=4, label=f"{label}: {zero.sum()} with 0 {what} (drawn at the floor)")
    a.set_xlabel("replan")
    a.set_title(f"{what} per replan", fontsize=9)
    a.legend(fontsize=7)


def split_at_slice(path: np.ndarray, zc: float) -> tuple[np.ndarray, np.ndarray, tuple]:
    """A plan (K, 3) as two polylines for a top view sliced at ``zc`` +- the slice: the
    parts inside the slice and the parts above or below it (each a (K, 3) array with NaN
    rows breaking it; empty when there is none), and the plan's (min, max) height. The
    parts join at the waypoints where the plan crosses the slice's edge."""
    p = np.asarray(path, dtype=float).reshape(-1, 3)
    if not len(p):
        return p, p, (zc, zc)
    out = np.abs(p[:, 2] - zc) > _SLICE
    near_out = out.copy()  # a segment with an end outside is drawn as outside
    near_out[:-1] |= out[1:]
    near_out[1:] |= out[:-1]
    inside, outside = p.copy(), p.copy()
    inside[out] = np.nan
    outside[~near_out] = np.nan
    z = (float(p[:, 2].min()), float(p[:, 2].max()))
    return inside, (outside if out.any() else p[:0]), z


def frame_replans(replans: int, max_frames: int) -> np.ndarray:
    """Indices of the replans drawn: all when there are at most ``max_frames``, else
    evenly spaced ones, the first and the last always included."""
    if replans <= max_frames:
        return np.arange(replans)
    return np.unique(np.round(np.linspace(0, replans - 1, max_frames)).astype(np.int64))


def _extent(res) -> tuple[float, float, float, float]:
    xy = np.concatenate([res.points[_band(res), :2], res.trajectory[:, :2],
                         res.start[None, :2], res.goal[None, :2]])
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.03 * float(max(hi - lo)) + 0.1
    return lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad


def _observed_masks(res, steps: np.ndarray, ext, shape) -> list[np.ndarray]:
    """Observed area at each of ``steps`` (move counts, ascending): the union of the
    horizontal scan polygons up to that scan, rasterised on a (ny, nx) grid."""
    from matplotlib.path import Path as MPath

    ny, nx = shape
    xs = np.linspace(ext[0], ext[1], nx)
    ys = np.linspace(ext[2], ext[3], ny)
    gx, gy = np.meshgrid(xs, ys)
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    seen = np.zeros(nx * ny, bool)
    out, done = [], 0
    az = res.ring_azimuths
    full = len(az) and (az.max() - az.min()) > np.radians(350)
    for step in steps:
        for t in range(done, min(step + 1, len(res.ring_ranges))):
            o = res.trajectory[t, :2]
            d = res.ring_ranges[t]
            poly = o + d[:, None] * np.column_stack([np.cos(az), np.sin(az)])
            if not full:  # a sector: close it through the robot
                poly = np.vstack([o, poly])
            r = float(d.max()) + 1e-9
            near = np.abs(grid - o).max(axis=1) <= r  # test only the points in reach
            seen[near] |= MPath(poly).contains_points(grid[near])
        done = max(done, step + 1)
        out.append(seen.reshape(ny, nx).copy())
    return out


def animate_gif(res, path: str | Path, max_frames: int = 150, fps: float = 6.0,
                dpi: int = 90) -> Path:
    """Animated GIF of the run, one frame per replan (at most ``max_frames``, evenly
    subsampled, the last replan always shown, plus a final frame at the end of the run).
    Written atomically with matplotlib's PillowWriter; returns the path.

    Parameters
    ----------
    res : ExploreResult
    path : str or Path
        Output ``.gif``.
    max_frames : int
        Upper bound on the replan frames (>= 1).
    fps : float
        Frames per second.
    """
    plt = _pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    if isinstance(max_frames, bool) or not isinstance(max_frames, int) or max_frames < 1:
        raise PlanError(f"max_frames must be a positive integer, got {max_frames!r}")
    if not res.replans:
        raise PlanError("nothing to animate: the run made no plan")
    picks = frame_replans(res.replans, max_frames)
    steps = [int(res.replan_step[j]) for j in picks]
    labels = [f"replan {j + 1}/{res.replans}" for j in picks]
    paths = [res.paths[j] for j in picks]
    end = len(res.trajectory) - 1
    steps.append(end)  # the end of the run: where the robot stopped, and why
    labels.append(f"end: {res.status}")
    paths.append(paths[-1][min(len(paths[-1]) - 1, end - steps[-2]):])
    ext = _extent(res)
    w = 7.0
    h = max(3.0, min(9.0, w * (ext[3] - ext[2]) / (ext[1] - ext[0]) + 1.2))
    nx = 360
    ny = max(20, int(nx * (ext[3] - ext[2]) / (ext[1] - ext[0])))
    masks = _observed_masks(res, np.asarray(steps), ext, (ny, nx))

    band = _band(res)
    zc = float(np.median(res.trajectory[:, 2]))
    pts = res.points[band]
    seen_step = res.seen_step[band]
    fig, ax = plt.subplots(figsize=(w, h))
    ax.set_facecolor("0.82")
    img = ax.imshow(np.zeros((ny, nx)), extent=ext, origin="lower", cmap="gray", vmin=0,
                    vmax=1, interpolation="nearest", zorder=0)
    ax.scatter(pts[:, 0], pts[:, 1], s=0.2, c="0.6", zorder=1, label="obstacles not seen yet")
    seen_sc = ax.scatter([], [], s=0.6, c="k", zorder=2, label="seen obstacles")
    (traj,) = ax.plot([], [], "-", c="tab:red", lw=1.6, zorder=4, label="trajectory")
    (plan,) = ax.plot([], [], "--", c="tab:blue", lw=1.4, zorder=3, label="current plan")
    (plan_out,) = ax.plot([], [], ":", c="magenta", lw=2.2, zorder=3,
                          label="plan above or below the slice")
    ax.plot(*res.start[:2], "o", c="tab:green", ms=6, zorder=5, label="start")
    ax.plot(*res.goal[:2], "*", c="gold", mec="k", ms=14, zorder=5, label="goal")
    robot = plt.Circle((0, 0), max(res.radius, 0.05), color="tab:red", alpha=0.6, zorder=6)
    ax.add_patch(robot)
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    dots = [Line2D([], [], ls="", marker="o", ms=3, c=c, label=lab)
            for c, lab in (("0.6", "obstacles not seen yet"), ("k", "seen obstacles"))]
    lines = [h for h in ax.get_legend_handles_labels()[0] if isinstance(h, Line2D)]
    handles = dots + lines + [
        Patch(facecolor="white", edgecolor="0.5", label="swept by the sensor"),
        Patch(facecolor="0.82", edgecolor="0.5", label="not observed")]
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.12),
              ncol=3, frameon=False)
    title = ax.set_title("")
    fig.tight_layout()

    def draw(k: int):
        step = steps[k]
        img.set_data(masks[k].astype(float) * 0.18 + 0.82)  # observed: white
        seen_sc.set_offsets(pts[(seen_step >= 0) & (seen_step <= step), :2])
        tr = res.trajectory[:step + 1]
        traj.set_data(tr[:, 0], tr[:, 1])
        inside, outside, z_range = split_at_slice(paths[k], zc)
        plan.set_data(inside[:, 0], inside[:, 1])
        plan_out.set_data(outside[:, 0], outside[:, 1])
        robot.center = (float(tr[-1, 0]), float(tr[-1, 1]))
        d = float(np.linalg.norm(np.diff(tr, axis=0), axis=1).sum())
        leaves = (f"; plan leaves the slice: z {z_range[0]:.1f}-{z_range[1]:.1f} m"
                  if len(outside) else "")
        title.set_text(f"{res.lattice}: {labels[k]}, {step} moves, {d:.1f} m travelled\n"
                       f"(slice z = {zc:.1f} +- {_SLICE} m{leaves})")
        return img, seen_sc, traj, plan, plan_out, robot, title

    anim = FuncAnimation(fig, draw, frames=len(steps), blit=False)
    out = Path(path)
    with atomic_path(out, keep_suffix=True) as tmp:
        anim.save(tmp, writer=PillowWriter(fps=fps), dpi=dpi)
    plt.close(fig)
    return out
