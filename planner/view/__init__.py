"""Interactive 3D view of a world and its paths: one self-contained HTML file.

``planner view MAP|WORLD.npz --path P.json --out view.html`` (and ``--view view.html`` on
``plan``, ``compare`` and ``explore``) writes a page that opens in any browser with no
network: orbit (left drag), zoom (wheel), pan (right drag); toggles for the raw points, the
blocked cells, the unknown cells, each path and the start / goal markers; a height slice
slider (hides everything above z); a read-out of the coordinates under the cursor; cells
drawn as squares the size of the cell (face-neighbour spacing) or as small points.

Large worlds stay responsive because each layer is one point buffer (one draw call) and
the page holds at most ``max_cells`` cells per layer: hidden interior cells are dropped and
the rest uniformly decimated, as the page's notes say (:mod:`planner.view.scene`).

>>> from planner import World, Lattice
>>> w = World(Lattice.named("bcc", 0.001), [[0, 0, 0], [1, 1, 1]], [[-0.2] * 3, [0.2] * 3])
>>> page = render_view(w, paths={"a": [[-0.1, 0, 0], [0.1, 0.05, 0]]})
>>> page.startswith("<!DOCTYPE html>"), "<script src" in page
(True, False)
"""

from __future__ import annotations

from planner.view.write import read_path_file, render_view, write_view

__all__ = ["read_path_file", "render_view", "write_view"]
