"""Regenerate the bundled maps: ``python -m planner.maps [OUT_DIR] [--seed N]``.

Writes ``<name>.ply`` and ``<name>.json`` for every map in :data:`planner.maps.MAPS`, by
default into the package's own data folder; the output is byte-for-byte deterministic.
"""

import argparse
import sys

from planner import maps

parser = argparse.ArgumentParser(prog="python -m planner.maps", description=__doc__.splitlines()[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
parser.add_argument("out_dir", nargs="?", default=str(maps.MAPS_DIR), help="output folder")
parser.add_argument("--seed", type=int, default=0, help="0 gives the bundled maps")
args = parser.parse_args()
for name, (ply, _) in maps.generate_all(args.out_dir, seed=args.seed).items():
    n = maps.load_map_info(ply)["n_points"]
    print(f"{name:15s} {n:8d} points {ply.stat().st_size / 1e6:6.2f} MB  {ply}")
from planner.maps.floorplan import generate_floorplan  # noqa: E402 - the 2D map

pgm, _, _ = generate_floorplan(args.out_dir)
print(f"{'floorplan':15s} {'2D':>8s} map    {pgm.stat().st_size / 1e6:6.2f} MB  {pgm}")
sys.exit(0)
