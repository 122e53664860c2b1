"""Map sidecars: the JSON file next to a map giving its bounds, robot radius and queries."""

from __future__ import annotations

import json
import math
from pathlib import Path

from planner.errors import MapError
from planner.io._files import decode_text, read_bytes


def sidecar_path(map_path: str | Path) -> Path:
    """The sidecar a map file would have: the same name with ``.json``."""
    p = Path(map_path)
    return p if p.suffix.lower() == ".json" else p.with_suffix(".json")


def load_sidecar(map_path: str | Path, *, required: tuple[str, ...] = ()) -> dict:
    """Read and validate the JSON sidecar of ``map_path`` (``{}`` when there is none).

    Known keys are checked for type and range; unknown keys pass through unchanged.

    ==================  =============================================================
    key                 value
    ==================  =============================================================
    ``bounds``          ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` (m), min <= max
    ``robot_radius``    number >= 0 (m)
    ``cell_volume``     number > 0 (m^3)
    ``clearance``       number >= 0 (m)
    ``queries``         list of ``{"start": [x, y, z], "goal": [x, y, z], "note": str}``
    ``file``, ``name``  strings
    ==================  =============================================================

    Parameters
    ----------
    map_path : str or Path
        The map file (or the sidecar itself).
    required : tuple of str
        Keys that must be present (a missing sidecar is then an error too).

    Raises
    ------
    MapError
        One line naming the sidecar and the key: unreadable JSON, not an object, a missing
        required key, or a value of the wrong type or range.
    """
    side = sidecar_path(map_path)
    if not side.exists():
        if required:
            raise MapError(f"{side}: map description not found")
        return {}
    try:
        info = json.loads(decode_text(read_bytes(side), side.name))
    except (ValueError, RecursionError) as exc:
        raise MapError(f"{side.name}: not valid JSON ({str(exc).splitlines()[0]})") from None
    if not isinstance(info, dict):
        raise MapError(f"{side.name}: must hold a JSON object, got {type(info).__name__}")
    for key in required:
        if key not in info:
            raise MapError(f"{side.name}: lacks the key '{key}'")
    where = side.name
    if "bounds" in info:
        b = _vectors(info["bounds"], 2, f"{where}: 'bounds'")
        if any(lo > hi for lo, hi in zip(*b, strict=True)):
            raise MapError(f"{where}: 'bounds' min corner exceeds the max corner")
        info["bounds"] = b
    for key, low, strict in (("robot_radius", 0.0, False), ("cell_volume", 0.0, True),
                             ("clearance", 0.0, False)):
        if key in info:
            info[key] = _number(info[key], f"{where}: '{key}'", low, strict)
    for key in ("file", "name", "description", "units", "up"):
        if key in info and not isinstance(info[key], str):
            raise MapError(f"{where}: '{key}' must be a string")
    if "queries" in info:
        qs = info["queries"]
        if not isinstance(qs, list):
            raise MapError(f"{where}: 'queries' must be a list")
        for i, q in enumerate(qs):
            if not isinstance(q, dict):
                raise MapError(f"{where}: 'queries'[{i}] must be an object")
            for end in ("start", "goal"):
                if end not in q:
                    raise MapError(f"{where}: 'queries'[{i}] lacks '{end}'")
                what = f"{where}: 'queries'[{i}].{end}"
                q[end] = _vectors([q[end]], 1, what)[0]
                if "bounds" in info and len(q[end]) != len(info["bounds"][0]):
                    raise MapError(f"{what} must have {len(info['bounds'][0])} numbers like "
                                   f"'bounds', got {len(q[end])}")
    return info


def _number(v, what: str, low: float, strict: bool) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise MapError(f"{what} must be a number, got {json.dumps(v)[:40]}")
    v = float(v)
    if not math.isfinite(v) or v < low or (strict and v == low):
        raise MapError(f"{what} must be {'>' if strict else '>='} {low:g}, got {v:g}")
    return v


def _vectors(v, rows: int, what: str) -> list[list[float]]:
    ok = (isinstance(v, list) and len(v) == rows
          and all(isinstance(r, list) and len(r) in (2, 3) for r in v)
          and len({len(r) for r in v}) == 1)
    if not ok:
        raise MapError(f"{what} must be {rows} list(s) of 2 or 3 numbers, got "
                       f"{json.dumps(v)[:40]}")
    return [[_number(x, what, -math.inf, False) for x in r] for r in v]
