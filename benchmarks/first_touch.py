"""Who pays for a query's first touch of memory: A* and Lazy Theta* on Warframe DA1
queries, three passes each, in both orders (A* first on 10 queries, then Lazy Theta* first
on 10 others that no search has touched).

The first search over a query's region takes the page faults of the slot map (4 KiB pages
of a 256 MB array on DA1), so a one-pass comparison charges them to whichever method runs
first; ``search_speed.py --repeat`` compares each query's fastest pass instead. Prints the
median kernel milliseconds per pass. Figures only; skips when the shared data is absent::

    python benchmarks/first_touch.py
"""

from __future__ import annotations

import sys

import numpy as np
from search_speed import WARFRAME, load_warframe

from planner import search as S


def main() -> int:
    if not WARFRAME.exists():
        print(f"no Warframe data at {WARFRAME}; skipping")
        return 0
    world, scen = load_warframe("DA1")
    qs = scen[:: len(scen) // 21][:21]
    s0, g0 = qs[0, :3].astype(np.int64), qs[0, 3:6].astype(np.int64)
    S.search(world, s0, g0, method="lazy-theta")  # kernels loaded outside the clock
    print("order              method        pass 1 ms  pass 2 ms  pass 3 ms  (medians, 10 queries)")
    for k, order in enumerate((("astar", "lazy-theta"), ("lazy-theta", "astar"))):
        ms = {m: [] for m in order}
        for q in qs[1 + 10 * k: 11 + 10 * k]:  # queries no earlier search touched
            s, g = q[:3].astype(np.int64), q[3:6].astype(np.int64)
            for _ in range(3):
                for m in order:
                    ms[m].append(1e3 * S.search(world, s, g, method=m).seconds)
        for m in order:
            med = np.median(np.array(ms[m]).reshape(10, 3), axis=0)
            print(f"{order[0] + ' first':18s} {m:12s} " + " ".join(f"{v:10.2f}" for v in med))
    return 0


if __name__ == "__main__":
    sys.exit(main())
