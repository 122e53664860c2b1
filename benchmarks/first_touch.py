"""Who pays for a query's first touch of memory: A* and Lazy Theta* on Warframe DA1
queries, three passes each, in both orders (A* first on 10 queries, then Lazy Theta* first
on 10 others that no search has touched).

The first search over a query's region takes the page faults of the slot map (4 KiB pages
of a 256 MB array on DA1), so a one-pass comparison charges them to whichever method runs
first; ``search_speed.py --repeat`` compares each query's fastest pass instead. Prints the
median engine milliseconds per pass (``SearchResult.seconds``) and, per method and order,
the paired ratio pass 1 / pass 3. Figures only; skips when the shared data is absent::

    python benchmarks/first_touch.py [--smoke] [--data DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)
from cpp_anchor import our_world, read_warframe  # noqa: E402

from planner import search as S  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=None, data=True)
    a = ap.parse_args(argv)
    name, per = ("Simple", 3) if a.smoke else ("DA1", 10)
    path = a.data / "warframe" / f"{name}.3dmap"
    with harness.session(f"first touch of memory: A* and Lazy Theta* on {name}",
                         smoke=a.smoke):
        if not path.exists():
            return harness.skip(f"no Warframe map at {path}")
        free, scen = read_warframe(path)
        world = our_world(free)
        qs = scen[:: len(scen) // (2 * per + 1)][: 2 * per + 1]
        s0, g0 = qs[0, :3].astype(np.int64), qs[0, 3:6].astype(np.int64)
        S.search(world, s0, g0, method="lazy-theta")  # kernels loaded outside the clock
        print(f"order              method        pass 1 ms  pass 2 ms  pass 3 ms  "
              f"(medians, {per} queries)")
        ratios = []
        for k, order in enumerate((("astar", "lazy-theta"), ("lazy-theta", "astar"))):
            ms = {m: [] for m in order}
            for q in qs[1 + per * k: 1 + per * (k + 1)]:  # queries no earlier search touched
                s, g = q[:3].astype(np.int64), q[3:6].astype(np.int64)
                for _ in range(3):
                    for m in order:
                        ms[m].append(1e3 * S.search(world, s, g, method=m).seconds)
            for m in order:
                passes = np.array(ms[m]).reshape(per, 3)
                med = np.median(passes, axis=0)
                print(f"{order[0] + ' first':18s} {m:12s} "
                      + " ".join(f"{v:10.2f}" for v in med))
                ratios.append((f"pass 1/pass 3 {m}, {order[0]} first", passes))
        for what, passes in ratios:
            print(harness.ratio_line(what, passes[:, 0], passes[:, 2],
                                     note="paired per query, engine time"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
