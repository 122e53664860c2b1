"""What re-verifying a saved world against its source map costs, against loading it alone
and against building it (thread CPU seconds, in one process).

Usage::

    python benchmarks/world_trust_cost.py [MAP] [--radius 0.2] [--repeat 3]
    python benchmarks/world_trust_cost.py --smoke     # the office at a coarse cell

A saved world is loaded (digest and schema checked), then rebuilt from its source and
compared cell for cell (``planner.world.trust.verify_world``): the check costs about one
build, which is what ``--trust-world`` skips when the source is at hand. The first build,
save and check (kernel compilation or cache load) are not timed; then the three take
turns, ``--repeat`` rounds, each round timed by this thread's CPU time
(``benchmarks/harness.py``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

import planner  # noqa: E402
from planner.world.file import load_world, save_world  # noqa: E402
from planner.world.trust import verify_world  # noqa: E402


def measure(name: str, radius: float, repeat: int, cell_volume: float | None) -> None:
    """Print the medians of build, load and load + verify, and their paired ratios."""
    def build():
        return planner.build_world(name, "fcc", radius=radius, cell_volume=cell_volume)

    with tempfile.TemporaryDirectory(prefix="world_trust_") as d:
        f = Path(d) / "w.npz"
        world = build()  # first run: kernels compiled or loaded, not timed
        save_world(world, f)
        verify_world(load_world(f), required=True)
        t = harness.interleaved(
            {"build": lambda _: harness.cpu(build),
             "load": lambda _: harness.cpu(lambda: load_world(f)),
             "verify": lambda _: harness.cpu(lambda: verify_world(load_world(f),
                                                                  required=True))},
            range(max(1, repeat)), 1)
    med = {k: float(np.median(v)) for k, v in t.items()}
    print(f"{name}, fcc, radius {radius:g} m, {len(world.blocked)} blocked cells "
          f"(CPU s, median of {max(1, repeat)} rounds)")
    print(f"  build from the map          {med['build']:.3f}")
    print(f"  load the saved world        {med['load']:.3f}")
    print(f"  load + verify against map   {med['verify']:.3f}")
    note = "paired per round, thread CPU"
    print(harness.ratio_line("load / build", t["load"], t["build"], note=note))
    print(harness.ratio_line("load + verify / build", t["verify"], t["build"], note=note))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("map", nargs="?", default="office", help="a map file or bundled map name")
    ap.add_argument("--radius", type=float, default=0.2, help="robot radius (m)")
    harness.add_arguments(ap, repeat=3)
    a = ap.parse_args(argv)
    with harness.session("saved-world verification against a build", smoke=a.smoke):
        if a.smoke:
            measure("office", a.radius, 2, 0.05)
        else:
            measure(a.map, a.radius, a.repeat, None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
