"""The one small benchmark suite the tests write, as TOML text, and a results row of it
(tests; the fuzz cases edit the text line by line, so its lines stay as they are)."""

from __future__ import annotations


def suite_text(name: str, *, seed: int | None = 1, queries: int = 1,
               path: str = "suite_map.xyz", cell_volume: float = 0.5,
               radius: float = 0.1) -> str:
    """A suite of one map, one lattice (cubic), face moves and A*: the TOML text.

    ``seed`` None leaves the line out (the suite's default seed)."""
    seed_line = "" if seed is None else f"seed = {seed}\n"
    return (f'name = "{name}"\n{seed_line}queries = {queries}\nlattices = ["cubic"]\n'
            'neighbors = ["face"]\nmethods = ["astar"]\nmin_distance = 0.3\n\n'
            f'[[maps]]\npath = "{path}"\ncell_volumes = [{cell_volume}]\n'
            f"radii = [{radius}]\n")


def result_row(**fields) -> dict:
    """A found row of :func:`suite_text`'s suite (A* on cubic, face moves, query 0), with
    ``fields`` replacing its values."""
    row = {"suite": "faults", "map": "m.xyz", "cell_volume": 0.5, "radius": 0.1,
           "rotation": 0, "lattice": "cubic", "neighbors": "face", "method": "astar",
           "seed": 0, "query": 0, "found": True, "length": 1.0, "length_smoothed": 1.0,
           "cell_checks": 3, "expansions": 2, "seconds": 0.01, "clearance": 0.2,
           "collision_free": True}
    return {**row, **fields}
