"""Scan-matching speed: the match score's cost per point lookup on every lattice against a
dedicated cubic rounding, and whole matches against the GICP anchors.

Run: ``python benchmarks/match_speed.py [--data ../shared/data] [--inits 6] [--repeat 3]
[--smoke]``.

1. **Per lookup** (Velodyne reference, 0.001 m^3 finest cells): the source's points (all
   64,685) scored at 64 poses near the truth on level 0 of each lattice by
   :meth:`planner.match.MultiResVoxelList.score` with the matcher's rounding (``cosets``,
   :mod:`planner.lattice.cosets`), with the generic exact quantizer (``generic``), and, as
   the baseline, with the rounding written for the cubic lattice only (``cubic``:
   ``x * (1/side)`` rounded, packed, looked up in the same hash set, on the cubic
   lattice's level). Every side is compiled by one untimed call; then the three sides take
   turns ``--repeat`` rounds per lattice (``benchmarks/harness.py``: this thread's CPU
   time) and each keeps its fastest, divided by points x poses, with the ratio to the
   dedicated cubic rounding of the same rounds. The three agree on every score (checked).
2. **Whole matches** (the Velodyne pair against ``relative.txt`` and the simulated geb079
   pairs, exact truth): the same ``--inits`` initial errors (up to 0.5 m, 10 degrees) for
   every method; lattices (4 levels, reference build included) and the anchors of
   :mod:`planner.match.anchor` (preprocessing included; the ``match`` extra); median CPU s
   per match, its ratio to GICP's, success (< 5 cm and < 1 degree) and median errors. The
   ``ratio`` lines pair each lattice's match with GICP's from the same start.

``--smoke``: 5,000 points at 8 poses, one round; the Velodyne pair only, one start.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.lattice import NAMED_LATTICES, Lattice  # noqa: E402
from planner.match import MultiResVoxelList, anchor, match, pose_error  # noqa: E402
from planner.match.experiment_pairs import draw_trial, geb079_pairs, velodyne_pair  # noqa: E402


def per_lookup(data: Path, repeat: int, smoke: bool) -> None:
    pair = velodyne_pair(data)
    rng = np.random.default_rng(0)
    n_poses = 8 if smoke else 64
    rots = Rotation.from_rotvec(rng.normal(scale=0.01, size=(n_poses, 3))).as_matrix() \
        @ pair.transform[:3, :3]
    trans = pair.transform[:3, 3] + rng.normal(scale=0.02, size=(n_poses, 3))
    pts = pair.source[:5000] if smoke else pair.source
    n = len(rots) * len(pts)

    cubic = MultiResVoxelList(pair.reference, Lattice.named("cubic", 0.001), 1)
    base_out = cubic.score(pts, rots, trans, rounding="cubic")  # compiles
    rows = {}
    for name in NAMED_LATTICES:
        mr = MultiResVoxelList(pair.reference, Lattice.named(name, 0.001), 1)
        outs = {k: mr.score(pts, rots, trans, rounding=k) for k in ("cosets", "generic")}
        assert np.array_equal(outs["cosets"], outs["generic"]), name
        if name == "cubic":
            assert np.array_equal(outs["cosets"], base_out)

        def side(mr, rounding):
            return lambda _: harness.cpu(lambda: mr.score(pts, rots, trans,
                                                          rounding=rounding))
        best = harness.interleaved({"cosets": side(mr, "cosets"),
                                    "generic": side(mr, "generic"),
                                    "cubic": side(cubic, "cubic")}, [name], repeat)
        rows[name] = ({k: float(v[0]) / n for k, v in best.items()},
                      mr.level(0).cosets.cosets)
    base = min(r["cubic"] for r, _ in rows.values())
    print(f"Per lookup: {len(pts)} points x {len(rots)} poses, best of {repeat} thread CPU "
          f"times, the sides taking turns")
    print(f"  dedicated cubic rounding (baseline)  {1e9 * base:5.1f} ns")
    print(f"  {'lattice':7s} {'cosets':>6s} {'matcher ns':>10s} {'x cubic':>8s} "
          f"{'generic ns':>10s} {'x cubic':>8s}")
    for name, (r, k) in rows.items():
        print(f"  {name:7s} {k:6d} {1e9 * r['cosets']:10.1f} {r['cosets'] / r['cubic']:8.2f} "
              f"{1e9 * r['generic']:10.1f} {r['generic'] / r['cubic']:8.2f}")
    for name, (r, _) in rows.items():
        print(harness.single_ratio(f"matcher lookup/dedicated cubic lookup on {name}",
                                   r["cosets"], r["cubic"], goal="<= 1.3",
                                   note=f"best of {repeat} rounds each"))


def _lattice_run(src, ref, name, init):
    def run():
        return match(src, MultiResVoxelList(ref, Lattice.named(name, 0.001), 4),
                     init=init).transform
    return harness.cpu_result(run)


def whole_matches(data: Path, inits: int, smoke: bool) -> None:
    pairs = [velodyne_pair(data)] + ([] if smoke else list(geb079_pairs(data)))
    methods = [*NAMED_LATTICES, *(anchor.ANCHORS if anchor.available() else ())]
    rows = {m: [] for m in methods}
    for i, p in enumerate(pairs):
        starts = [draw_trial(0, i, k, 0.5, 10.0).error @ p.transform for k in range(inits)]
        for m in methods:
            def run(init, m=m, p=p):
                if m in NAMED_LATTICES:
                    return _lattice_run(p.source, p.reference, m, init)
                return anchor.register(m, p.source, p.reference, init)  # its process CPU
            run(starts[0])  # untimed: compiles the kernels, fills the caches
            for s in starts:
                t, sec = run(s)
                rows[m].append((*pose_error(t, p.transform), sec, p.group))
    groups = [g for g in ("velodyne", "geb079") if any(r[3] == g for r in rows[methods[0]])]
    print(f"\nWhole matches: {len(pairs)} pairs x {inits} initial errors (<= 0.5 m, 10 deg); "
          f"median CPU s per match")
    ref = "gicp" if "gicp" in rows else methods[0]
    ref_s = {g: np.median([r[2] for r in rows[ref] if r[3] == g]) for g in groups}
    head = " | ".join(f"{g + ' s':>10s} {'x ' + ref:>10s}" for g in groups)
    print(f"  {'method':9s} {'success':>7s} {'pos mm':>7s} {'rot deg':>7s} | {head}")
    for m, rr in rows.items():
        a = np.array([r[:3] for r in rr])
        ok = ((a[:, 0] < 0.05) & (a[:, 1] < 1.0)).mean()
        cells = []
        for g in groups:
            s = np.median([r[2] for r in rr if r[3] == g])
            cells.append(f"{s:10.3f} {s / ref_s[g]:10.1f}")
        print(f"  {m:9s} {100 * ok:6.0f}% {1e3 * np.median(a[:, 0]):7.1f} "
              f"{np.median(a[:, 1]):7.3f} | " + " | ".join(cells))
    if ref == "gicp":
        base = [r[2] for r in rows["gicp"]]
        for m in NAMED_LATTICES:
            print(harness.ratio_line(f"{m} match/gicp CPU per match", [r[2] for r in rows[m]],
                                     base, goal="<= 5", note="paired by pair and start"))
    else:
        base = [r[2] for r in rows["cubic"]]
        print("(no GICP anchor: install the 'match' extra; lattices paired with cubic)")
        for m in NAMED_LATTICES[1:]:
            print(harness.ratio_line(f"{m} match/cubic match CPU per match",
                                     [r[2] for r in rows[m]], base,
                                     note="paired by pair and start"))


def main(argv=None) -> int:
    ap = harness.add_arguments(argparse.ArgumentParser(description=__doc__.split("\n")[0]),
                               repeat=3, data=True)
    ap.add_argument("--inits", type=int, default=6)
    ap.add_argument("--no-matches", action="store_true", help="per-lookup costs only")
    a = ap.parse_args(argv)
    with harness.session("match_speed: score lookups and whole matches", smoke=a.smoke):
        if not (a.data / "velodyne").is_dir():
            return harness.skip(f"no Velodyne data in {a.data}")
        per_lookup(a.data, 1 if a.smoke else a.repeat, a.smoke)
        if not a.no_matches:
            whole_matches(a.data, 1 if a.smoke else a.inits, a.smoke)
    return 0


if __name__ == "__main__":
    sys.exit(main())
