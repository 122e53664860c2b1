"""Regenerate the bundled example maps: ``python maps/generate.py [OUT_DIR] [--seed N]``.

Writes ``<name>.ply`` (binary little-endian float32 x, y, z) and ``<name>.json`` (sidecar: bounds,
suggested robot radius and cell volume, default queries) for every map in
``planner.maps.MAPS``; the output is byte-for-byte deterministic for a given seed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", nargs="?", default=str(here), help="default: this folder")
    parser.add_argument("--seed", type=int, default=0, help="default 0 (the bundled maps)")
    args = parser.parse_args(argv)
    try:
        from planner import maps
    except ImportError:  # running from a clone without `pip install -e .`
        sys.path.insert(0, str(here.parent))
        from planner import maps
    for name, (ply, js) in maps.generate_all(args.out_dir, seed=args.seed).items():
        info = maps.load_map_info(js)
        print(f"{name:15s} {info['n_points']:8d} points {ply.stat().st_size / 1e6:6.2f} MB  {ply}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
