"""Benchmark rows as OMPL's benchmark database (``planner_arena.db``), for Planner Arena.

The schema is the one ``ompl_benchmark_statistics.py`` creates (tables ``experiments``,
``plannerConfigs``, ``enums``, ``runs``, ``progress``), so Planner Arena and OMPL's own
scripts open the file as they open OMPL's. Mapping:

- one *experiment* per map x cell volume x radius x rotation (``name`` says which;
  ``runcount`` is the most queries a planner ran in it);
- one *planner* (``plannerConfigs`` row) per lattice x neighbours x method, named
  ``lattice_neighbours_method`` (e.g. ``bcc_full_astar``), its settings as JSON;
- one *run* per result row: ``time`` (s, the search time), ``solved`` (0/1),
  ``solution_length`` (m; NULL when unsolved), plus the project's own properties
  ``solution_smoothed_length`` (m), ``cell_checks`` and ``expansions``.
"""

from __future__ import annotations

import datetime
import errno
import json
import math
import os
import platform
import sqlite3

from planner import __version__
from planner.fsutil import atomic_path

__all__ = ["SCHEMA", "planner_name", "write_arena_db"]

SCHEMA = """
CREATE TABLE experiments (id INTEGER PRIMARY KEY AUTOINCREMENT, name VARCHAR(512),
    totaltime REAL, timelimit REAL, memorylimit REAL, runcount INTEGER, version VARCHAR(128),
    hostname VARCHAR(1024), cpuinfo TEXT, date DATETIME, seed VARCHAR(24), setup TEXT);
CREATE TABLE plannerConfigs (id INTEGER PRIMARY KEY AUTOINCREMENT,
    name VARCHAR(512) NOT NULL, settings TEXT);
CREATE TABLE enums (name VARCHAR(512), value INTEGER, description TEXT,
    PRIMARY KEY (name, value));
CREATE TABLE runs (id INTEGER PRIMARY KEY AUTOINCREMENT, experimentid INTEGER,
    plannerid INTEGER, time REAL, solved BOOLEAN, solution_length REAL,
    solution_smoothed_length REAL, cell_checks INTEGER, expansions INTEGER,
    FOREIGN KEY (experimentid) REFERENCES experiments(id) ON DELETE CASCADE,
    FOREIGN KEY (plannerid) REFERENCES plannerConfigs(id) ON DELETE CASCADE);
CREATE TABLE progress (runid INTEGER, time REAL, PRIMARY KEY (runid, time),
    FOREIGN KEY (runid) REFERENCES runs(id) ON DELETE CASCADE);
"""


def planner_name(row: dict) -> str:
    """``lattice_neighbours_method`` of a result row (``ompl:RRT`` -> ``ompl-RRT``)."""
    return "_".join(str(row.get(k, "-")).replace(":", "-")
                    for k in ("lattice", "neighbors", "method"))


def _num(x):
    return None if x is None or (isinstance(x, float) and not math.isfinite(x)) else x


def write_arena_db(out: str | os.PathLike, rows: list[dict], *, suite: str = "") -> int:
    """Write ``rows`` (the suite's result rows) as OMPL's benchmark database at ``out``,
    atomically; returns the number of runs written."""
    experiments: dict[tuple, list[dict]] = {}
    for r in rows:
        key = (str(r.get("map")), r.get("cell_volume"), r.get("radius"), r.get("rotation", 0))
        experiments.setdefault(key, []).append(r)
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S")
    with atomic_path(out) as tmp:
        tmp.unlink()  # sqlite creates its own file
        try:
            con = sqlite3.connect(tmp)
        except sqlite3.Error as exc:
            raise OSError(errno.EIO, f"cannot create the Planner Arena database: {exc}",
                          str(out)) from None
        try:
            con.executescript(SCHEMA)
            planners: dict[str, int] = {}
            n = 0
            for (m, cv, radius, rot), group in experiments.items():
                per: dict[str, int] = {}
                for r in group:
                    per[planner_name(r)] = per.get(planner_name(r), 0) + 1
                total = sum(float(r.get("seconds") or 0.0) for r in group)
                # OMPL's time budget (s); lattice searches have none (0 when only they ran)
                limit = max((float(r["time_limit"]) for r in group
                             if r.get("time_limit") is not None), default=0.0)
                setup = json.dumps({"suite": suite, "map": m, "cell_volume": cv,
                                    "radius": radius, "rotation": rot})
                cur = con.execute(
                    "INSERT INTO experiments (name, totaltime, timelimit, memorylimit, runcount,"
                    " version, hostname, cpuinfo, date, seed, setup) VALUES "
                    "(?,?,?,?,?,?,?,?,?,?,?)",
                    (f"{suite} {os.path.basename(m)} cell volume {cv:g} radius {radius:g} "
                     f"rotation {rot}", total, limit, 0.0, max(per.values()),
                     f"lattice-planner {__version__}", platform.node(), None, date, "0", setup))
                exp_id = cur.lastrowid
                for r in group:
                    name = planner_name(r)
                    if name not in planners:
                        settings = json.dumps({k: r.get(k) for k in
                                               ("lattice", "neighbors", "method")})
                        planners[name] = con.execute(
                            "INSERT INTO plannerConfigs (name, settings) VALUES (?, ?)",
                            (name, settings)).lastrowid
                    found = bool(r.get("found"))
                    con.execute(
                        "INSERT INTO runs (experimentid, plannerid, time, solved, "
                        "solution_length, solution_smoothed_length, cell_checks, expansions)"
                        " VALUES (?,?,?,?,?,?,?,?)",
                        (exp_id, planners[name], _num(r.get("seconds")), int(found),
                         _num(r.get("length")) if found else None,
                         _num(r.get("length_smoothed")) if found else None,
                         r.get("cell_checks"), r.get("expansions")))
                    n += 1
            con.commit()
        except sqlite3.Error as exc:  # a full disk ("database or disk is full"), I/O errors
            code = errno.ENOSPC if "full" in str(exc) else errno.EIO
            raise OSError(code, f"cannot write the Planner Arena database: {exc}",
                          str(out)) from None
        finally:
            con.close()
    return n
