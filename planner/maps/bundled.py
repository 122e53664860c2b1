"""Bundled example maps: seeded generators and the generated files, shipped as package data.

Every map is a point cloud of *sensor-like surface samples*: points on the visible surfaces
(floors, ceilings, walls, shelves, trunks, ...) as a laser scanner would return them, on a
jittered grid of about one point per ``spacing x spacing`` of surface, with 5 mm gaussian noise
on every coordinate.  Solids are never filled.  Units are metres, z is up.

The files live in ``planner/maps/data/`` inside the installed package (``<name>.ply``, binary
little endian float32 x, y, z, and a sidecar ``<name>.json``), so a map is addressable by name
from anywhere (``planner compare office``); ``python -m planner.maps`` regenerates them byte
for byte.

Sidecar keys: ``name``, ``description``, ``file`` (the PLY file name), ``units``, ``up``,
``seed``, ``n_points``, ``sample_spacing``, ``noise_sigma``, ``bounds``
(``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``, the world box a planner must stay in; every point
lies inside it up to noise), ``robot_radius`` (suggested), ``cell_volume`` (suggested lattice cell
volume in m^3), ``clearance`` (the distance every default query keeps from every point:
``2 * robot_radius + 0.1``), ``queries`` (list of ``{"start", "goal", "note"}``) and, for some
maps, ``extra`` (map specific documented dimensions).

Every default query is checked when a map is built: both ends lie inside the bounds, at least
``clearance`` away from every point, and the straight segment between them passes closer than
``robot_radius`` to some point (so the query needs a real route).  A violation raises
:class:`planner.errors.MapError`.

Examples
--------
>>> from planner import maps
>>> sorted(maps.MAPS)
['forest', 'narrow_passage', 'office', 'two_storey', 'warehouse']
>>> maps.resolve("office").name
'office.ply'
>>> maps.read_sidecar(maps.resolve("office"))["robot_radius"]
0.25
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from planner.errors import MapError
from planner.fsutil import write_text_atomic
from planner.io import load_points, load_sidecar, save_points
from planner.maps._sampling import NOISE_SIGMA
from planner.maps._scenes import build

__all__ = [
    "MAPS",
    "MAPS_DIR",
    "NOISE_SIGMA",
    "build",
    "forest",
    "generate",
    "generate_all",
    "load_map_info",
    "load_map_points",
    "map_path",
    "narrow_passage",
    "office",
    "read_sidecar",
    "resolve",
    "two_storey",
    "warehouse",
]

MAPS_DIR = Path(__file__).resolve().parent / "data"
"""Directory of the bundled map files (package data: ``planner/maps/data``)."""



def office(seed: int = 0) -> np.ndarray:
    """Office floor 20 x 12 x 3 m: corridor, eight rooms, 0.9 x 2.1 m doors. (N, 3) points."""
    return build("office", seed)[0]


def two_storey(seed: int = 0) -> np.ndarray:
    """Two 12 x 8 x 3 m floors joined by a stairwell. (N, 3) points."""
    return build("two_storey", seed)[0]


def warehouse(seed: int = 0) -> np.ndarray:
    """Warehouse 30 x 20 x 6 m with six shelf racks and 2 m aisles. (N, 3) points."""
    return build("warehouse", seed)[0]


def forest(seed: int = 0) -> np.ndarray:
    """Forest 30 x 30 m: uneven ground, 70-90 trunks, a few crowns. (N, 3) points."""
    return build("forest", seed)[0]


def narrow_passage(seed: int = 0) -> np.ndarray:
    """Two 6 x 6 x 3 m chambers joined by a 3 m passage 0.7 m wide, 1 m high. (N, 3) points."""
    return build("narrow_passage", seed)[0]


MAPS: dict[str, Callable[..., np.ndarray]] = {
    "office": office,
    "two_storey": two_storey,
    "warehouse": warehouse,
    "forest": forest,
    "narrow_passage": narrow_passage,
}
"""Registry: map name -> generator ``f(seed=0) -> np.ndarray (N, 3)``."""


def _write_json(path: Path, info: dict[str, Any]) -> None:
    text = json.dumps(info, indent=2) + "\n"
    # one line per innermost list of numbers: "start": [2.0, 2.0, 1.178]
    text = re.sub(r"\[\s+([-+0-9.eE,\s]+?)\s+\]",
                  lambda m: "[" + ", ".join(v.strip() for v in m.group(1).split(",")) + "]", text)
    write_text_atomic(path, text)


def generate(name: str, out_dir: str | os.PathLike[str], seed: int = 0) -> tuple[Path, Path]:
    """Write ``<name>.ply`` and ``<name>.json`` into ``out_dir``; return both paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    points, info = build(name, seed)
    ply, js = out / f"{name}.ply", out / f"{name}.json"
    save_points(ply, points, dtype=np.float32)
    _write_json(js, info)
    return ply, js


def generate_all(out_dir: str | os.PathLike[str] = MAPS_DIR, seed: int = 0
                 ) -> dict[str, tuple[Path, Path]]:
    """Generate every map in :data:`MAPS` into ``out_dir``: name -> (ply path, json path)."""
    return {name: generate(name, out_dir, seed) for name in MAPS}


def map_path(name: str) -> Path:
    """Path of the bundled point cloud ``<name>.ply``; MapError if unknown or missing."""
    if name not in MAPS:
        raise MapError(f"unknown map {name!r}; known: {sorted(MAPS)}")
    path = MAPS_DIR / f"{name}.ply"
    if not path.is_file():
        raise MapError(f"bundled map file {path} is missing; run `python -m planner.maps`")
    return path


def resolve(name_or_path: str | os.PathLike[str]) -> Path:
    """A map argument as a path: an existing file as given, else a bundled map by name.

    ``"office"`` (or ``"office.ply"``) resolves to the bundled file when no such file exists
    in the current folder, so the bundled maps work from any directory.  Other strings are
    returned unchanged as paths (the reader reports a missing file).
    """
    p = Path(name_or_path)
    if p.exists():
        return p
    if p.name == "floorplan" and p.parent == Path("."):  # the bundled 2D map (ROS map)
        return MAPS_DIR / "floorplan.yaml"
    stem = p.name[:-4] if p.name.endswith(".ply") else p.name
    if stem in MAPS and p.parent == Path("."):
        return map_path(stem)
    return p


def read_sidecar(map_path: str | os.PathLike[str]) -> dict[str, Any]:
    """The checked JSON sidecar beside a map file (``{}`` when it has none).

    The one sidecar reader is :func:`planner.io.load_sidecar`; this name is kept for the
    maps' callers.
    """
    return load_sidecar(map_path)


def load_map_info(name_or_path: str | os.PathLike[str]) -> dict[str, Any]:
    """Sidecar info of a bundled map name, a ``.json`` sidecar path or a ``.ply`` path.

    The returned dict is the JSON content plus ``"ply_path"``: the absolute path of the
    point-cloud file next to the sidecar.
    """
    if isinstance(name_or_path, str) and name_or_path in MAPS:
        js = MAPS_DIR / f"{name_or_path}.json"
    else:
        p = Path(name_or_path)
        js = p if p.suffix.lower() == ".json" else p.with_suffix(".json")
    info = load_sidecar(js, required=("bounds", "queries"))
    info["ply_path"] = str((js.parent / info.get("file", js.with_suffix(".ply").name)).resolve())
    return info


def load_map_points(name_or_path: str | os.PathLike[str]) -> np.ndarray:
    """Points (N, 3) float64 of a bundled map name or of a point-cloud file."""
    path = map_path(name_or_path) if isinstance(name_or_path, str) and name_or_path in MAPS \
        else Path(name_or_path)
    return np.asarray(load_points(path), dtype=np.float64)
