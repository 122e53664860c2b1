"""World growth: build time, peak memory, saved size and one long query as cells shrink.

Usage::

    python benchmarks/world_scaling.py                          # geb079 at 0.16, 0.08, 0.04 m
    python benchmarks/world_scaling.py --edges 0.16,0.08,0.04,0.02 --lattices cubic,fcc
    python benchmarks/world_scaling.py --synthetic 1e6,1e7,1e8  # box-field map instead
    python benchmarks/world_scaling.py --smoke                  # the hall at 1e5, 3e5 cells

Maps: ``geb079`` (``../shared/data/octomap/geb079.bt``, an OctoMap of a building corridor,
robot radius 0.2 m, unknown space blocked), cell edge ``h`` (cell volume ``h**3``); or
``--synthetic``: a seeded field of axis-aligned boxes in a 32 x 32 x 8 m hall (unknown
space free), its cell edge chosen so that the world's index box holds about N cells.

Each row runs in a process of its own (peak memory is per process), after a warm-up build
and plan on a small map (no JIT time in any figure), with the peak-RSS mark reset after the
warm-up (``/proc/self/clear_refs``):

* build: CPU seconds of :func:`planner.build_world` (``time.process_time``, one core);
* peak: the process's peak resident memory over build + save + plan (VmHWM, MB), and the
  part above its memory before the build ("world + plan");
* file: bytes of the saved world (:func:`planner.world.file.save_world`);
* query: one long A* query (:func:`planner.plan` defaults) between the free cells nearest
  to two fixed points (geb079: 11 m apart along the corridor; the hall: corner to corner):
  this thread's CPU seconds of the ``plan()`` call, expansions and the search's own arrays
  (``PlanResult.peak_bytes``).

The exponents are least-squares slopes of log(quantity) against log(blocked cells) over the
rows of one lattice (1.0: grows as the blocked cells do). The machine may be shared: trust
the exponents and ratios of one run more than absolute times. No assertions: it prints.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

GEB = harness.DATA / "octomap" / "geb079.bt"
HALL = np.array([[0.0, 0.0, 0.0], [32.0, 32.0, 8.0]])


def synthetic_map(cells: float, seed: int = 0):
    """The box-field hall and the cell edge (m) giving about ``cells`` box cells."""
    from planner.io import Obstacles

    rng = np.random.default_rng(seed)
    n = 400  # cubes (edge: the largest of three draws) standing on the floor
    size = rng.uniform(0.3, 2.0, (n, 3))
    centre = rng.uniform(HALL[0] + 1, HALL[1] - 1, (n, 3))
    centre[:, 2] = size[:, 2] / 2
    edge = (float(np.prod(HALL[1] - HALL[0])) / cells) ** (1 / 3)
    obst = Obstacles(points=np.zeros((0, 3)), boxes=centre, box_size=float(size.max()),
                     box_sizes=size.max(axis=1), bounds=HALL, resolution=None,
                     source="synthetic-hall")
    return obst, edge


# one long connected query on geb079 (along the corridor, 11 m apart) and across the hall
GEB_QUERY = np.array([[15.37, -0.76, 2.16], [26.54, -0.63, 1.02]])
HALL_QUERY = np.array([[0.5, 0.5, 0.5], [31.5, 31.5, 0.5]])


def _endpoints(world, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The free cell centres (m) nearest to the two points of ``query`` (2, 3)."""
    ends = []
    for p in query:
        cell = world.lattice.quantize(p[None])[0]
        near = world.nearest_free(cell, max_radius=2.0)
        if near is None:
            raise SystemExit(f"no free cell near {p}")
        ends.append(world.lattice.to_world(near[None])[0])
    return ends[0], ends[1]


def child(spec: str, geb: Path = GEB) -> dict:
    """One row (in this process): ``geb:<lattice>:<edge>`` or ``syn:<lattice>:<cells>``."""
    import planner
    from planner.world.file import save_world

    kind, lattice, value = spec.split(":")
    warm = planner.build_world(geb if kind == "geb" else synthetic_map(1e5)[0], lattice,
                               cell_volume=0.32**3 if kind == "geb" else 1.0, radius=0.2,
                               unknown="blocked" if kind == "geb" else "free")
    query = GEB_QUERY if kind == "geb" else HALL_QUERY
    planner.plan(warm, *_endpoints(warm, query))
    del warm
    if kind == "geb":
        obst, edge, policy = planner.io.load_obstacles(geb), float(value), "blocked"
    else:
        obst, edge = synthetic_map(float(value))
        policy = "free"
    harness.reset_peak_rss()
    before = harness.rss() or 0
    t0 = time.process_time()
    world = planner.build_world(obst, lattice, cell_volume=edge**3, radius=0.2, unknown=policy)
    build = time.process_time() - t0
    build_peak = harness.peak_rss() or 0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "w.npz"
        save_world(world, path)
        size = path.stat().st_size
    a, b = _endpoints(world, query)
    res, query_cpu = harness.cpu_result(lambda: planner.plan(world, a, b))
    occ = world.occupancy
    return {"lattice": lattice, "edge": edge, "box": int(np.prod(occ.dims)),
            "blocked": world.n_blocked, "unknown": world.n_unknown, "build": build,
            "build_peak": build_peak, "peak": harness.peak_rss() or 0, "before": before,
            "file": size, "found": res.found, "search": query_cpu,
            "expansions": res.expansions, "search_bytes": res.peak_bytes,
            "storage": world.storage}


def _run(spec: str, geb: Path) -> dict | str:
    """One row in a process of its own, or the last line of its error (the row failed)."""
    out = subprocess.run([sys.executable, __file__, "--child", spec, "--geb", str(geb)],
                         capture_output=True, text=True, env=os.environ.copy())
    if out.returncode != 0:
        lines = out.stderr.strip().splitlines() or ["no output"]
        return lines[-1]
    return json.loads(out.stdout.strip().splitlines()[-1])


def _slope(x: list[float], y: list[float]) -> str:
    if len(x) < 2 or min(x) <= 0 or min(y) <= 0:
        return "-"
    return f"{np.polyfit(np.log(x), np.log(y), 1)[0]:.2f}"


def table(rows: list[dict]) -> str:
    """The growth table and the exponents per lattice."""
    mb = 2**20
    head = ("lattice  edge m     box cells      blocked  build CPU s  peak MB  world+plan MB"
            "  bits/box cell  file KB  query s  expansions  search MB  found")
    lines = [head]
    for r in rows:
        above = r["peak"] - r["before"]
        lines.append(
            f"{r['lattice']:7s} {r['edge']:7.4f} {r['box']:13,d} {r['blocked']:12,d} "
            f"{r['build']:12.2f} {r['peak'] / mb:8.0f} {above / mb:14.0f} "
            f"{8 * above / r['box']:14.2f} {r['file'] / 1024:8.0f} {r['search']:8.3f} "
            f"{r['expansions']:11,d} {r['search_bytes'] / mb:10.1f}  {r['found']}")
    lines.append("")
    lines.append("exponents against blocked cells (least squares over the rows of a lattice):")
    lines.append("lattice  build CPU  world+plan memory  file size  query s  search memory")
    for lat in dict.fromkeys(r["lattice"] for r in rows):
        rs = [r for r in rows if r["lattice"] == lat]
        x = [r["blocked"] for r in rs]
        lines.append(f"{lat:7s} {_slope(x, [r['build'] for r in rs]):>10s} "
                     f"{_slope(x, [r['peak'] - r['before'] for r in rs]):>18s} "
                     f"{_slope(x, [r['file'] for r in rs]):>10s} "
                     f"{_slope(x, [r['search'] for r in rs]):>8s} "
                     f"{_slope(x, [max(r['search_bytes'], 1) for r in rs]):>14s}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--edges", default="0.16,0.08,0.04", help="geb079 cell edges (m)")
    ap.add_argument("--lattices", default="cubic,fcc")
    ap.add_argument("--synthetic", default="", help="box cells of the synthetic hall, e.g. "
                    "1e6,1e7,1e8 (instead of geb079)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--geb", type=Path, help=argparse.SUPPRESS)
    harness.add_arguments(ap, repeat=None, data=True)
    a = ap.parse_args(argv)
    if a.child:
        print(json.dumps(child(a.child, a.geb)))
        return 0
    if a.smoke:
        a.synthetic, a.lattices = "1e5,3e5", "cubic"
    with harness.session("world growth as cells shrink", smoke=a.smoke):
        return _measure(a)


def _measure(a) -> int:
    geb = a.data / "octomap" / "geb079.bt"
    if not a.synthetic and not geb.is_file():
        return harness.skip(f"no geb079 at {geb}")
    rows, failed = [], []
    for lat in a.lattices.split(","):
        if a.synthetic:
            specs = [f"syn:{lat}:{v}" for v in a.synthetic.split(",")]
        else:
            specs = [f"geb:{lat}:{v}" for v in a.edges.split(",")]
        for spec in specs:
            got = _run(spec, geb)
            if isinstance(got, str):  # printed under the table, left out of it
                failed.append(f"{spec} failed: {got}")
                print(f"  {failed[-1]}", file=sys.stderr, flush=True)
                continue
            rows.append(got)
            print(f"  {spec}: {got['build']:.2f} s, {got['peak'] / 2**20:.0f} MB",
                  file=sys.stderr, flush=True)
    print(table(rows))
    for line in failed:
        print(line)
    for lat in dict.fromkeys(r["lattice"] for r in rows):
        rs = sorted((r for r in rows if r["lattice"] == lat), key=lambda r: r["blocked"])
        if len(rs) >= 2 and rs[0]["blocked"] and rs[-1]["blocked"]:
            print(harness.single_ratio(
                f"build CPU per blocked cell, largest / smallest row, {lat}",
                rs[-1]["build"] / rs[-1]["blocked"], rs[0]["build"] / rs[0]["blocked"],
                note="1: linear in the blocked cells"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
