"""Size and load time of the 3D view of geb079 (BCC, 0.2 m radius, one path) in headless
Chromium.

    PYTHONPATH=. python benchmarks/view_load.py [--repeats 3] [--smoke] [--data DIR]

Prints the HTML size, the embedded library's share of it, and per load the time from
navigation to the page's first drawn frame (the page's own clock) and to the driver seeing
it (both include parsing and decoding the embedded arrays; wall time: a browser's). Needs
../shared/data and chromium + chromedriver (one ``skipped:`` line otherwise). ``--smoke``:
the bundled office map, one load.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from importlib import resources
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.cli import main as planner  # noqa: E402
from planner.view.browser import find_browser, open_page  # noqa: E402


def run(repeats: int, data: Path, smoke: bool = False) -> int:
    geb = data / "octomap" / "geb079.bt"
    if isinstance(find_browser(), str):
        return harness.skip("needs chromium + chromedriver")
    if not smoke and not geb.is_file():
        return harness.skip(f"needs {geb}")
    with tempfile.TemporaryDirectory() as d:
        w, p, html = Path(d, "geb.npz"), Path(d, "p.json"), Path(d, "v.html")
        if smoke:
            planner(["world", "office", "--lattice", "bcc", "--out", str(w)])
            planner(["plan", str(w), "--start", "2.5,2.5,1.2", "--goal", "18.3,10.5,1.2",
                     "--out", str(p)])
        else:
            planner(["world", str(geb), "--lattice", "bcc", "--radius", "0.2", "--out",
                     str(w)])
            planner(["plan", str(w), "--start=-5.9,-0.87,0.81", "--goal", "8.38,-0.71,0.55",
                     "--out", str(p)])
        planner(["view", str(w), "--path", str(p), "--out", str(html)])
        size = html.stat().st_size
        assets = resources.files("planner.view") / "assets"
        lib = sum(len((assets / n).read_bytes()) for n in ("three.min.js", "OrbitControls.js"))
        page, driver = [], []
        for _ in range(repeats):
            r = open_page(html)
            page.append(r.state["readyMs"] / 1000)
            driver.append(r.seconds)
    print(f"html size: {size / 1e6:.2f} MB ({lib / 1e6:.2f} MB of it three.js + controls)")
    print(f"first frame, page clock: median {statistics.median(page):.2f} s of {repeats}")
    print(f"ready seen by the driver: median {statistics.median(driver):.2f} s of {repeats}")
    print(harness.ratio_line("driver ready / page first frame", driver, page,
                             note="paired per load, wall"))
    print(harness.single_ratio("three.js + controls / html size", lib, size))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    harness.add_arguments(ap, repeat=None, data=True)
    a = ap.parse_args(argv)
    with harness.session("3D view load time in headless Chromium", smoke=a.smoke):
        return run(1 if a.smoke else a.repeats, a.data, a.smoke)


if __name__ == "__main__":
    sys.exit(main())
