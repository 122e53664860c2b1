"""The one schema of a suite file: every key's type, range and length, checked before
anything is run, each failure one line naming the key.

Keys (``planner bench --help`` prints this table)::

    name          a label (letters, digits, space, _ . + - ( ); at most 100 characters);
                  never a path: the default output folder is results/<name>
    seed          integer 0..4294967295 (queries and rotations)
    queries       integer 1..1000000 per map x cell volume x radius x rotation
    lattices      non-empty list of lattice names (cubic, bcc, fcc, mcc, hex)
    neighbors     non-empty list of move sets (face, full, face+K, full+K)
    methods       list of lattice methods, or "explore"; may be empty only when
                  [ompl] planners names at least one planner
    min_distance  start-goal distance as a fraction of the map box's diagonal, in (0, 1)
    rotation      "none" | "yaw" | "so3";  rotations: integer 1..1000000
    kind          "planning" (default) | "paper" (the paper's measurements, [paper] table)
    [ompl]        planners (list), time (seconds > 0), seeds (list of 0..4294967295),
                  lattice (name): a continuous baseline checked on that lattice's world
    [paper]       rotations (1..1000000), samples (100..10^9), seed (0..4294967295),
                  volumes (non-empty list of positive numbers), quick (true | false)
    [explore]     exploration runs (needs "explore" in methods)
    [[maps]]      path (bundled map name, or a file relative to the suite's folder, then the
                  current folder); cell_volumes (or cell_volume): positive numbers (m^3);
                  radii (or radius): numbers >= 0 (m); scenarios (a .3dscen file instead of
                  sampling); queries (integer 1..1000000, this map's own count)

A suite file is at most 1 MB, nested at most 4 tables deep, with strings of at most 4096
characters, no NUL, and lists of at most 10000 entries.
"""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

from planner.errors import PlannerError

__all__ = ["SuiteError", "parse_suite", "check_suite_table", "label_ok", "KEYS_HELP"]

KEYS_HELP = __doc__.split("Keys (``planner bench --help`` prints this table)::\n\n", 1)[1]
"""The keys' table above, for ``planner bench --help``."""

MAX_BYTES = 1 << 20
MAX_DEPTH = 4  # the top table, [[maps]] (a list of tables) and a value list inside one
MAX_STRING = 4096
MAX_LIST = 10_000
MAX_SEED = 2**32 - 1
_LABEL = re.compile(r"[^\W_][\w .+()-]{0,99}")


class SuiteError(PlannerError):
    """A suite file that cannot be run."""


def label_ok(name: str) -> bool:
    """``name`` is a label that cannot be read as a path: no separator, NUL, ``..`` or
    leading dot; at most 100 characters."""
    return bool(_LABEL.fullmatch(name)) and ".." not in name


def parse_suite(path: Path) -> dict:
    """The TOML table of the suite file ``path``, its size and nesting bounded.

    Raises
    ------
    SuiteError
        Unreadable, over 1 MB, not TOML, or nested too deep (one line naming the file).
    """
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise SuiteError(f"{path}: a suite file is at most 1 MB, this one is {size} bytes")
        text = path.read_text(encoding="utf-8")
        return tomllib.loads(text)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SuiteError(f"{path}: not a valid TOML suite: {exc}") from None
    except RecursionError:  # tomllib parses nested arrays and inline tables recursively
        raise SuiteError(f"{path}: not a valid TOML suite: arrays or tables nested too deep "
                         f"(at most {MAX_DEPTH} levels)") from None


def _walk(path: Path, value, key: str, depth: int) -> None:
    """Depth, string and list bounds of every value (iterative in effect: depth is capped)."""
    if depth > MAX_DEPTH:
        raise SuiteError(f"{path}: {key!r} is nested too deep (at most {MAX_DEPTH} levels)")
    if isinstance(value, str):
        if "\x00" in value:
            raise SuiteError(f"{path}: {key!r} contains a NUL character")
        if len(value) > MAX_STRING:
            raise SuiteError(f"{path}: {key!r} is longer than {MAX_STRING} characters")
    elif isinstance(value, list):
        if len(value) > MAX_LIST:
            raise SuiteError(f"{path}: {key!r} has more than {MAX_LIST} entries")
        for v in value:
            _walk(path, v, key, depth + 1)
    elif isinstance(value, dict):
        for k, v in value.items():
            if "\x00" in k or len(k) > 100:
                raise SuiteError(f"{path}: a key in {key or 'the suite'!r} is not a name")
            _walk(path, v, f"{key}.{k}" if key else k, depth + 1)
    elif isinstance(value, float) and not math.isfinite(value):
        raise SuiteError(f"{path}: {key!r} must be finite, got {value}")


_KEYS = {"": {"name", "seed", "queries", "lattices", "neighbors", "methods", "min_distance",
              "ompl", "maps", "kind", "paper", "rotation", "rotations", "explore"},
         "maps": {"path", "cell_volumes", "cell_volume", "radii", "radius", "scenarios",
                  "queries"},
         "ompl": {"planners", "time", "seeds", "lattice"},
         "paper": {"rotations", "volumes", "samples", "seed", "quick"}}
_LISTS = ("lattices", "neighbors", "methods")


def _number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _integer(v, lo: int, hi: int) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi


def check_suite_table(path: Path, raw: dict) -> None:
    """Refuse unknown keys and values of the wrong type, range or length, naming the key (a
    typo must not silently fall back to a default)."""
    def bad(key: str, want: str) -> SuiteError:
        return SuiteError(f"{path}: {key!r} must be {want}")

    def unknown(table: dict, where: str) -> None:
        extra = sorted(set(table) - _KEYS[where])
        if extra:
            at = f" in [{where}]" if where else ""
            raise SuiteError(f"{path}: unknown key {extra[0]!r}{at} (known: "
                             f"{', '.join(sorted(_KEYS[where]))})")

    _walk(path, raw, "", 0)
    unknown(raw, "")
    for key, lo, hi in (("queries", 1, 10**6), ("seed", 0, MAX_SEED),
                        ("rotations", 1, 10**6)):
        if not _integer(raw.get(key, lo), lo, hi):
            raise bad(key, f"an integer in {lo}..{hi}")
    _check_paper(raw, bad, unknown)
    d = raw.get("min_distance", 0.3)
    if not _number(d) or not 0 < d < 1:
        raise bad("min_distance", "a number in (0, 1): the start-goal distance as a fraction "
                  "of the map box's diagonal")
    for key in _LISTS:  # methods may be empty: an OMPL-only suite
        v = raw.get(key, ["x"])
        if not isinstance(v, list) or not (v or key == "methods") or not all(
                isinstance(x, str) for x in v):
            raise bad(key, "a non-empty list of names")
    name = raw.get("name", "x")
    if not isinstance(name, str) or not label_ok(name):
        raise bad("name", "a label of at most 100 letters, digits, spaces or _ . + - ( ) "
                  "(not a path)")
    if not isinstance(raw.get("rotation", "none"), str):
        raise bad("rotation", '"none", "yaw" or "so3"')
    if not isinstance(raw.get("kind", "planning"), str) or raw.get("kind") not in (
            None, "planning", "paper"):
        raise bad("kind", '"planning" or "paper"')
    maps = raw.get("maps", [])
    if not isinstance(maps, list) or not all(isinstance(m, dict) for m in maps):
        raise bad("maps", "a list of [[maps]] tables")
    for m in maps:
        _check_map(m, bad, unknown)
    ex = raw.get("explore", {})
    if not isinstance(ex, dict):
        raise bad("explore", "an [explore] table")
    if ex and "explore" not in raw.get("methods", ()):
        raise SuiteError(f"{path}: an [explore] table needs \"explore\" in methods")
    from planner.bench.explore_rows import check_explore_table  # lazy: scipy

    why = check_explore_table(ex)
    if why:
        raise SuiteError(f"{path}: {why}")
    _check_ompl(raw, bad, unknown)
    if (raw.get("kind", "planning") == "planning" and raw.get("methods") == []
            and not raw.get("ompl", {}).get("planners")):
        raise SuiteError(f"{path}: 'methods' is empty and [ompl] names no planners: the "
                         f"suite would run nothing")


def _check_map(m: dict, bad, unknown) -> None:
    unknown(m, "maps")
    if not isinstance(m.get("path"), str) or not m["path"]:
        raise bad("maps.path", "a file name or a bundled map name")
    if not isinstance(m.get("scenarios", ""), str):
        raise bad("maps.scenarios", "a file name")
    if not _integer(m.get("queries", 1), 1, 10**6):
        raise bad("maps.queries", "an integer in 1..1000000")
    for many, one, lo_ok, want in (
            ("cell_volumes", "cell_volume", lambda v: 0 < v, "positive numbers (m^3)"),
            ("radii", "radius", lambda v: 0 <= v, "numbers >= 0 (m)")):
        if many in m and one in m:
            raise bad(f"maps.{many}", f"given once (not with maps.{one})")
        vals = m[many] if many in m else [m[one]] if one in m else None
        key = f"maps.{many}" if many in m else f"maps.{one}"
        if vals is None:
            if many == "cell_volumes":
                raise bad("maps.cell_volumes", "given: a list of positive numbers (m^3)")
            continue  # radius 0: a point robot
        if not isinstance(vals, list) or not vals or not all(
                _number(v) and lo_ok(v) and math.isfinite(v) for v in vals):
            raise bad(key, f"a non-empty list of {want}" if many in m else f"one of {want}")


def _check_paper(raw: dict, bad, unknown) -> None:
    paper = raw.get("paper", {})
    if not isinstance(paper, dict):
        raise bad("paper", "a [paper] table")
    unknown(paper, "paper")
    for key, lo, hi in (("rotations", 1, 10**6), ("samples", 100, 10**9),
                        ("seed", 0, MAX_SEED)):
        if not _integer(paper.get(key, lo), lo, hi):
            raise bad(f"paper.{key}", f"an integer in {lo}..{hi}")
    vols = paper.get("volumes", [1.0])
    if not isinstance(vols, list) or not vols or not all(
            _number(x) and 0 < x < math.inf for x in vols):
        raise bad("paper.volumes", "a non-empty list of positive cell volumes")
    if not isinstance(paper.get("quick", False), bool):
        raise bad("paper.quick", "true or false")


def _check_ompl(raw: dict, bad, unknown) -> None:
    ompl = raw.get("ompl", {})
    if not isinstance(ompl, dict):
        raise bad("ompl", "an [ompl] table")
    unknown(ompl, "ompl")
    planners = ompl.get("planners", [])
    if not isinstance(planners, list) or not all(isinstance(x, str) for x in planners):
        raise bad("ompl.planners", "a list of planner names")
    if not isinstance(ompl.get("lattice", "cubic"), str):
        raise bad("ompl.lattice", "a lattice name")
    t = ompl.get("time", 1.0)
    if not _number(t) or not 0 < t < math.inf:
        raise bad("ompl.time", "a positive number of seconds")
    seeds = ompl.get("seeds", [0])
    if not isinstance(seeds, list) or not seeds or not all(
            _integer(x, 0, MAX_SEED) for x in seeds):
        raise bad("ompl.seeds", "a non-empty list of integers in 0..4294967295")
