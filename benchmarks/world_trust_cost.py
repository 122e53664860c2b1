"""What re-verifying a saved world against its source map costs, against loading it alone
and against building it (CPU seconds, best of a few repeats, in one process).

    python benchmarks/world_trust_cost.py [MAP] [RADIUS]

A saved world is loaded (digest and schema checked), then rebuilt from its source and
compared cell for cell (planner.world.trust.verify_world): the check costs about one build,
which is what ``--trust-world`` skips when the source is at hand.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import planner
from planner.world.file import load_world, save_world
from planner.world.trust import verify_world


def cpu(fn, repeats: int = 3) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "office"
    radius = float(sys.argv[2]) if len(sys.argv) > 2 else 0.2
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "w.npz"
        world = planner.build_world(name, "fcc", radius=radius)  # first run: JIT, not timed
        save_world(world, f)
        verify_world(load_world(f), required=True)
        build = cpu(lambda: planner.build_world(name, "fcc", radius=radius))
        load = cpu(lambda: load_world(f))
        check = cpu(lambda: verify_world(load_world(f), required=True))
    print(f"{name}, fcc, radius {radius:g} m, {len(world.blocked)} blocked cells "
          f"(CPU s, best of 3)")
    print(f"  build from the map          {build:.3f}")
    print(f"  load the saved world        {load:.3f}  ({load / build:.2f} x build)")
    print(f"  load + verify against map   {check:.3f}  ({check / build:.2f} x build)")


if __name__ == "__main__":
    main()
