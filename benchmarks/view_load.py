"""Size and load time of the 3D view of geb079 (BCC, 0.2 m radius, one path) in headless
Chromium.

    PYTHONPATH=. python benchmarks/view_load.py [--repeats 3]

Prints the HTML size, the embedded library's share of it, and per load the time from
navigation to the page's first drawn frame (the page's own clock) and to the driver seeing
it (both include parsing and decoding the embedded arrays). Needs ../shared/data and
chromium + chromedriver.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from importlib import resources
from pathlib import Path

from planner.cli import main as planner
from planner.view.browser import find_browser, open_page

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"


def run(repeats: int) -> int:
    geb = DATA / "octomap" / "geb079.bt"
    if not geb.is_file() or isinstance(find_browser(), str):
        print("needs ../shared/data and chromium + chromedriver", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as d:
        w, p, html = Path(d, "geb.npz"), Path(d, "p.json"), Path(d, "v.html")
        planner(["world", str(geb), "--lattice", "bcc", "--radius", "0.2", "--out", str(w)])
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
    return 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    sys.exit(run(ap.parse_args().repeats))
