"""How much the verification of a saved world costs: ``load_world`` (checked reads, schema,
digest) against a plain ``numpy.load`` of the same arrays, in the same process.

Usage::

    python benchmarks/world_load.py WORLD.npz [--repeat 7]
    python benchmarks/world_load.py --smoke          # a world of the bundled office map

WORLD.npz is a world from ``planner world``, e.g. ``planner world
../shared/data/octomap/geb079.bt --radius 0.2 --out geb079.npz``. The first call of each
(imports, the check kernel's compilation or cache load) is not timed; then the two take
turns, ``--repeat`` rounds, each timed by this thread's CPU time
(``benchmarks/harness.py``). Prints the medians and the paired ratio per round.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.world.file import load_world, save_world  # noqa: E402


def _plain(path: str) -> None:
    with np.load(path, allow_pickle=False) as z:
        for k in z.files:
            z[k]


def measure(path: str, repeat: int) -> None:
    """Print the medians of both loads and their paired ratio."""
    _plain(path)  # not timed: first use
    w = load_world(path)
    t = harness.interleaved({"plain": lambda _: harness.cpu(lambda: _plain(path)),
                             "checked": lambda _: harness.cpu(lambda: load_world(path))},
                            range(max(1, repeat)), 1)
    plain, checked = float(np.median(t["plain"])), float(np.median(t["checked"]))
    print(f"{path}: {w.n_blocked} blocked, {w.n_unknown} unknown cells")
    print(f"numpy.load {plain * 1e3:.1f} ms, load_world {checked * 1e3:.1f} ms "
          f"(medians of {max(1, repeat)}, CPU)")
    print(harness.ratio_line("load_world / numpy.load", t["checked"], t["plain"],
                             note="paired per round, thread CPU"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("world", nargs="?", help="a saved world (.npz)")
    harness.add_arguments(ap, repeat=7)
    a = ap.parse_args(argv)
    with harness.session("load_world against numpy.load", smoke=a.smoke):
        if a.smoke or a.world is None:
            if not a.smoke:
                ap.error("give WORLD.npz (or --smoke)")
            from planner import build_world

            with tempfile.TemporaryDirectory(prefix="world_load_") as d:
                path = str(Path(d) / "office.npz")
                save_world(build_world("office", "bcc"), path)
                measure(path, 3)
            return 0
        measure(a.world, a.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
