"""Bundled example maps: seeded generators and the generated files, shipped as package data.

Everything lives in :mod:`planner.maps.bundled` (the registry, generation and lookup) and the
scene generators (:mod:`planner.maps._scenes`, :mod:`planner.maps.floorplan`).
"""

from planner.maps.bundled import (
    MAPS,
    MAPS_DIR,
    NOISE_SIGMA,
    build,
    forest,
    generate,
    generate_all,
    load_map_info,
    load_map_points,
    map_path,
    narrow_passage,
    office,
    read_sidecar,
    resolve,
    two_storey,
    warehouse,
)

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
