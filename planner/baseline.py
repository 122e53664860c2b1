"""OMPL (PyPI ``ompl`` 2.0.1, nanobind bindings) as the continuous-space baseline.

The OMPL planners search ``RealVectorStateSpace(3)`` with the world's bounds on exactly the
same occupancy as the lattice planners:

* **State validity**: the lattice cell containing the state is in bounds and free. A Python
  callable reads the three coordinates and calls one compiled (numba) kernel that quantizes
  the point (the exact generic closest-point kernel of :mod:`planner.lattice._quantize`)
  and does one occupancy lookup (:func:`planner._search_kernels.cell_free`). One check.
* **Motion validity**: the 2.0.1 bindings let Python subclass ``ob.MotionValidator``
  (``checkMotion(s1, s2)``), so motions are validated with the EXACT lattice segment walk
  (:func:`planner._search_kernels.segment_walk`, the lattice planners' line-of-sight test):
  a motion is valid iff every cell whose closed Voronoi cell the segment touches is free.
  Every cell looked at is counted. No interpolation resolution is involved, so no blocked
  cell can be skipped (a resolution-based check would need a step below the smallest
  distance a segment can travel inside a cell's corner, which is 0, so no finite step is
  exact). The longest-valid-segment fraction is therefore irrelevant and left at default.
  OMPL's ``checkMotion(s1, s2, lastValid)`` overload is not overridable from Python; the
  planners used here (and the path simplifier) call the two-state form.
* The parent process re-validates every returned segment with :meth:`World.segment_free`
  anyway (defence in depth: a path is never reported found unless that passes).

Process guard: OMPL runs in a worker process (``forkserver`` context with ``ompl`` and this
module preloaded, so a query costs a fork, not a fresh interpreter) with a hard timeout.
A segfault or a hang gives ``found=False`` and a reason. The worker leaves with
``os._exit`` after sending its result, which skips interpreter finalisation and with it
nanobind's "leaked instances" report (the bindings' object graph is cyclic via Python
callbacks; the report is noise at exit).

Termination and time to first solution: a ``PlannerTerminationCondition`` built from a
Python function stops at the time limit, when the cell-check budget is exceeded, or (for
non-anytime planners) at the first exact solution; it records the first time a solution
exists (``pdef.hasExactSolution()`` or a finite ``planner.bestCost()``: RRT* and BIT* add
their solution to the problem definition only when ``solve`` returns). Planners that
evaluate the termination condition in a helper thread (PRM, PRM*) deadlock with a Python
condition (``solve`` keeps the GIL), so they are run in short slices with the C++
``timedPlannerTerminationCondition`` (PRM keeps its roadmap between ``solve`` calls) and the
first solution / budget are checked between slices (resolution: one slice).

OMPL 2.0.1 quirks: ``SimpleSetup.setup()`` without a planner segfaults (reported; not used
here); ``getPlannerProgressProperties`` and ``setIntermediateSolutionCallback`` are not
usable from Python (no type casters); ``lbtrrt``, ``lazyprmstar``, ``sst``, ``aitstar`` are
not bound; SORRT* hung in a prototype (handled by the guard); AORRTC reports "Invalid
goal" with a goal state; InformedRRT* found no solution on the office query within 2 s
where RRT* needs 0.3-0.5 s, with identical check counts for seeds 0 and 1 (its informed
sampler seems not to follow ``RNG.setSeed``); ``RealVectorBounds.low[i] = x`` writes to a
copy and is silently lost (use ``setLow(i, x)``); a forked worker must get the lattice
tables and occupancy from the parent (rebuilding them means ~0.7 s of lattice geometry
LPs) and arrays of the same writability as at warm-up (else numba recompiles).
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import pickle
import sys
import time
import types
from typing import Any

import numpy as np
from numba import njit

from planner import _search_kernels as sk
from planner.errors import PlanError
from planner.lattice import _quantize as qk
from planner.world import World, _walk_data

__all__ = ["PLANNERS", "ANYTIME", "plan_ompl", "run_seeds", "CompiledChecker", "lattice_tables"]

#: canonical name -> ``ompl.geometric`` class name (what the 2.0.1 bindings expose).
PLANNERS: dict[str, str] = {
    "rrtconnect": "RRTConnect",
    "rrt": "RRT",
    "rrtstar": "RRTstar",
    "informedrrtstar": "InformedRRTstar",
    "sorrtstar": "SORRTstar",
    "bitstar": "BITstar",
    "prm": "PRM",
    "prmstar": "PRMstar",
    "fmt": "FMT",
    "bfmt": "BFMT",
    "kpiece1": "KPIECE1",
    "bkpiece1": "BKPIECE1",
    "lbkpiece1": "LBKPIECE1",
    "aorrtc": "AORRTC",
}
_ALIASES = {"rrt*": "rrtstar", "rrt-connect": "rrtconnect", "informed-rrtstar": "informedrrtstar",
            "bit*": "bitstar", "prm*": "prmstar", "kpiece": "kpiece1", "bkpiece": "bkpiece1",
            "lbkpiece": "lbkpiece1"}
#: asymptotically optimal planners: keep improving until the time limit.
ANYTIME = frozenset({"rrtstar", "informedrrtstar", "sorrtstar", "bitstar", "prm", "prmstar",
                     "aorrtc"})
#: planners that evaluate the termination condition in a helper thread (see module doc).
_THREADED = frozenset({"prm", "prmstar"})
_EXTRA_TIMEOUT = 30.0  # s beyond the time limit before the worker is killed
_WARM_ENV = "PLANNER_BASELINE_WARM"


# -- compiled validity ---------------------------------------------------------------------
@njit(cache=True)
def _state_free(occ, q, x0, x1, x2, buf, out):  # pragma: no cover - compiled
    """Is the cell containing point (x0, x1, x2) (m) in bounds and free? One lookup."""
    qb, qbinv, cand, cand_z, counts, t = q
    buf[0, 0] = x0
    buf[0, 1] = x1
    buf[0, 2] = x2
    qk.quantize_generic3(buf[:1], qb, qbinv, cand, cand_z, counts, t, out)
    return sk.cell_free(occ, out[0, 0], out[0, 1], out[0, 2])


@njit(cache=True)
def _motion_free(occ, q, walk, a0, a1, a2, b0, b1, b2, buf, out):  # pragma: no cover
    """Exact segment test a -> b (m): ``(all touched cells free, lookups made)``."""
    qb, qbinv, cand, cand_z, counts, t = q
    g, rel, rhs, full = walk
    buf[0, 0] = a0
    buf[0, 1] = a1
    buf[0, 2] = a2
    buf[1, 0] = b0
    buf[1, 1] = b1
    buf[1, 2] = b2
    qk.quantize_generic3(buf[:1], qb, qbinv, cand, cand_z, counts, t, out)
    _, free, n = sk.segment_walk(occ, buf[0], buf[1], out[0], g, rel, rhs, full, True)
    return free, n


class CompiledChecker:
    """Counting state / motion checks on a world through compiled kernels.

    Parameters
    ----------
    world : World
    tables : tuple, optional
        :func:`lattice_tables` of the world's lattice (computed if not given).

    Attributes
    ----------
    checks : int
        Occupancy lookups made (one per state, one per cell looked at per motion).
    states, motions : int
        Number of state and motion queries.
    """

    def __init__(self, world: World, tables: tuple | None = None):
        self._q, self._walk = tables if tables is not None else lattice_tables(world.lattice)
        # One numba signature for every world: read-only arrays (cached lattice data) are a
        # different numba type and would force a multi-second recompile in each worker.
        self._occ = _writable(world.occupancy)
        self._buf = np.zeros((2, 3))
        self._out = np.zeros((1, 3), dtype=np.int64)
        self.checks = 0
        self.states = 0
        self.motions = 0

    def point_free(self, x: float, y: float, z: float) -> bool:
        """Cell of the point (m) in bounds and free (one counted lookup)."""
        self.checks += 1
        self.states += 1
        return bool(_state_free(self._occ, self._q, float(x), float(y), float(z), self._buf,
                                self._out))

    def segment_free(self, a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
        """Exact lattice segment walk a -> b (m); counts every cell looked at."""
        free, n = _motion_free(self._occ, self._q, self._walk, float(a[0]), float(a[1]),
                               float(a[2]), float(b[0]), float(b[1]), float(b[2]), self._buf,
                               self._out)
        self.checks += n
        self.motions += 1
        return bool(free)


def lattice_tables(lat) -> tuple[tuple, tuple]:
    """Kernel inputs of a lattice: the exact generic quantizer's tables (as in
    ``Lattice.quantize_generic``) and the segment-walk data. Computed in the parent and
    shipped to the worker: deriving them (``Lattice._geo``) costs ~0.8 s per new lattice."""
    geo = lat._geo
    b = np.array(geo["reduced"], dtype=float)
    cand_z = np.array(geo["orthant_offsets"], dtype=np.int64)
    q = (b, np.linalg.inv(b), np.ascontiguousarray(cand_z.astype(float) @ b.T), cand_z,
         np.array(geo["orthant_counts"], dtype=np.int64),
         np.array(geo["reduction"], dtype=float))
    return _writable(q), _writable(_walk_data(lat))


def _writable(items: tuple) -> tuple:
    return tuple(np.array(x) if isinstance(x, np.ndarray) and not x.flags.writeable else x
                 for x in items)


# -- public API ----------------------------------------------------------------------------
def canonical_planner(name: str) -> str:
    """Canonical planner name; PlanError listing the valid ones if unknown."""
    key = str(name).strip().lower().replace("_", "")
    key = _ALIASES.get(key, key)
    if key not in PLANNERS:
        raise PlanError(f"unknown OMPL planner {name!r}; expected one of "
                        f"{', '.join(PLANNERS)}")
    return key


def _length(path) -> float:
    p = np.asarray(path, dtype=float).reshape(-1, 3)
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) if len(p) > 1 else 0.0


def _path_valid(world: World, path) -> bool:
    p = np.asarray(path, dtype=float).reshape(-1, 3)
    if len(p) < 1 or not world.points_free(p[:1])[0]:
        return False
    return all(world.segment_free(p[i], p[i + 1]) for i in range(len(p) - 1))


def plan_ompl(
    world: World,
    start,
    goal,
    *,
    planner: str = "rrtconnect",
    time_limit: float = 1.0,
    seed: int = 0,
    max_cell_checks: int | None = None,
    simplify: bool = True,
    verbose: bool = False,
    timeout: float | None = None,
) -> dict:
    """Plan with an OMPL planner on the world's occupancy, in a guarded worker process.

    Parameters
    ----------
    world : World
    start, goal : array_like, shape (3,)
        Points (m); each must lie in a free cell (else PlanError).
    planner : str
        A key of :data:`PLANNERS` (unknown names raise PlanError listing them).
    time_limit : float
        Planning budget (s). Anytime planners (:data:`ANYTIME`) use all of it; the others
        stop at the first solution.
    seed : int
        OMPL's global RNG seed (``ou.RNG.setSeed``) in the worker.
    max_cell_checks : int, optional
        Also stop once this many occupancy lookups were made.
    simplify : bool
        Run ``og.PathSimplifier.simplify`` (budget ``min(time_limit, 1 s)``) on a copy.
    verbose : bool
        Let OMPL log (LOG_INFO) instead of silencing it.
    timeout : float, optional
        Hard wall-clock limit of the worker (s), default ``time_limit + 30``.

    Returns
    -------
    dict
        ``found``, ``path`` / ``path_raw`` ((K, 3) list, start first, goal last),
        ``path_simplified`` ((K', 3) list or None), ``length_raw``, ``length_simplified``
        (m, None if absent), ``cell_checks`` (worker lookups), ``seconds`` (planning +
        simplification wall time in the worker), ``time_to_first_solution`` (s or None),
        ``final_cost`` (m), ``planner``, ``seed``, ``valid_raw``, ``valid_simplified``
        (re-validated here with :meth:`World.segment_free`), ``checks_per_second``,
        ``reason`` ('' on success), plus ``wall_seconds`` (including the process),
        ``state_checks``, ``motion_checks``, ``status``.
    """
    name = canonical_planner(planner)
    if not (isinstance(time_limit, int | float) and math.isfinite(time_limit) and time_limit > 0):
        raise PlanError(f"time_limit must be a positive number of seconds, got {time_limit!r}")
    s, _ = world.endpoint(start, "start")
    g, _ = world.endpoint(goal, "goal")
    hard = float(timeout) if timeout is not None else float(time_limit) + _EXTRA_TIMEOUT
    base: dict[str, Any] = {
        "found": False, "path": [], "path_raw": [], "path_simplified": None,
        "length_raw": None, "length_simplified": None, "cell_checks": 0, "seconds": 0.0,
        "time_to_first_solution": None, "final_cost": None, "planner": name, "seed": int(seed),
        "valid_raw": None, "valid_simplified": None, "checks_per_second": 0.0, "reason": "",
        "wall_seconds": 0.0, "state_checks": 0, "motion_checks": 0, "status": "",
    }
    t0 = time.perf_counter()
    # Ship the occupancy and lattice tables: the worker would otherwise rederive the
    # lattice geometry (LPs, ~0.7 s) that the parent has cached.
    tables = (lattice_tables(world.lattice), world.occupancy)
    out = _run_guarded(world, tables, s, g, name, float(time_limit), int(seed),
                       max_cell_checks, bool(simplify), bool(verbose), hard)
    base.update(out)
    base["wall_seconds"] = time.perf_counter() - t0
    raw = base.get("path_raw") or []
    if base["found"]:
        base["valid_raw"] = _path_valid(world, raw)
        if not base["valid_raw"]:
            base.update(found=False, reason="raw path touched a blocked cell (rejected)")
        elif base["path_simplified"] is not None:
            base["valid_simplified"] = _path_valid(world, base["path_simplified"])
            if not base["valid_simplified"]:
                base.update(path_simplified=None, length_simplified=None,
                            reason="simplified path touched a blocked cell; kept raw path")
    if not base["found"]:
        base.update(path=[], path_raw=[], path_simplified=None, length_raw=None,
                    length_simplified=None)
    else:
        base["path"] = raw
    return base


def run_seeds(world: World, start, goal, seeds, **kw) -> list[dict]:
    """:func:`plan_ompl` once per seed (same keyword arguments); list of result dicts."""
    return [plan_ompl(world, start, goal, seed=int(sd), **kw) for sd in seeds]


# -- process guard -------------------------------------------------------------------------
_CTX = None


def _context():
    """forkserver (preloading ompl and this module) where available, else spawn."""
    global _CTX
    if _CTX is None:
        if "forkserver" in mp.get_all_start_methods():
            from multiprocessing import forkserver

            _CTX = mp.get_context("forkserver")
            _CTX.set_forkserver_preload(["numpy", "numba", "ompl.base", "ompl.geometric",
                                         "ompl.util", "planner.baseline"])
            # Start the server now with the warm-up flag so that it loads the compiled
            # kernels once and every forked worker inherits them (saves ~1 s per query).
            os.environ[_WARM_ENV] = "1"
            try:
                forkserver.ensure_running()
            finally:
                os.environ.pop(_WARM_ENV, None)
        else:  # pragma: no cover - non-POSIX
            _CTX = mp.get_context("spawn")
    return _CTX


def _run_guarded(world, tables, s, g, name, time_limit, seed, max_checks, simplify, verbose,
                 hard) -> dict:
    ctx = _context()
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_worker, args=(send, world, tables, s, g, name, time_limit,
                                             seed, max_checks, simplify, verbose), daemon=True)
    # The child must not re-run the caller's script (spawn-style start methods import
    # ``__main__`` from its path): everything it runs lives in this package, so present a
    # bare ``__main__`` while the preparation data is taken. Callers then need no
    # ``if __name__ == "__main__"`` guard.
    main = sys.modules.get("__main__")
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        proc.start()
    finally:
        if main is not None:
            sys.modules["__main__"] = main
    send.close()  # so that recv sees EOF if the worker dies
    deadline = time.monotonic() + hard
    result = None
    try:
        while result is None:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            if recv.poll(min(left, 0.5)):
                try:
                    result = recv.recv()
                except EOFError:
                    break
            elif not proc.is_alive() and not recv.poll(0):
                break
    finally:
        recv.close()
    if result is not None:
        proc.join(5.0)
        if proc.is_alive():  # pragma: no cover - sent its result but did not exit
            proc.kill()
            proc.join()
        return result
    if proc.is_alive():
        proc.kill()
        proc.join()
        return {"reason": f"timeout: worker killed after {hard:g} s", "status": "timeout"}
    proc.join()
    code = proc.exitcode
    why = f"crashed (signal {-code})" if code is not None and code < 0 else (
        f"worker exited with code {code} without a result")
    return {"reason": why, "status": "crashed"}


def _worker(conn, world, tables, s, g, name, time_limit, seed, max_checks, simplify,
            verbose):
    """Worker body: plan, send a plain dict, leave without finalisation (module doc)."""
    try:
        try:
            res = _solve(world, tables, s, g, name, time_limit, seed, max_checks, simplify,
                         verbose)
        except Exception as exc:  # report, not raise: the parent decides
            res = {"found": False, "reason": f"worker error: {type(exc).__name__}: {exc}",
                   "status": "error"}
        conn.send(res)
        conn.close()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)


def _states(path) -> list[list[float]]:
    return [[float(st[0]), float(st[1]), float(st[2])] for st in path.getStates()]


def _solve(world, tables, s, g, name, time_limit, seed, max_checks, simplify,
           verbose) -> dict:
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_INFO if verbose else ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(int(seed))
    tables, occ = tables
    world._occ = occ  # dropped by World pickling; rebuilding needs the lattice geometry
    chk = CompiledChecker(world, tables)
    chk.point_free(*s)  # compile / load the kernels before the clock starts
    chk.segment_free(s, g)
    chk.checks = chk.states = chk.motions = 0

    space = ob.RealVectorStateSpace(3)
    bounds = ob.RealVectorBounds(3)
    lo, hi = world.bounds
    for i in range(3):
        bounds.setLow(i, float(lo[i]))  # bounds.low[i] = x edits a copy (silently lost)
        bounds.setHigh(i, float(hi[i]))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    si.setStateValidityChecker(lambda st: chk.point_free(st[0], st[1], st[2]))

    class _Exact(ob.MotionValidator):
        def checkMotion(self, a, b):  # noqa: N802 - OMPL's name
            return chk.segment_free((a[0], a[1], a[2]), (b[0], b[1], b[2]))

    mv = _Exact(si)
    si.setMotionValidator(mv)
    si.setup()
    pdef = ob.ProblemDefinition(si)
    a, b = space.allocState(), space.allocState()
    for i in range(3):
        a[i] = float(s[i])
        b[i] = float(g[i])
    pdef.setStartAndGoalStates(a, b)
    obj = ob.PathLengthOptimizationObjective(si)
    pdef.setOptimizationObjective(obj)
    pl = getattr(og, PLANNERS[name])(si)
    pl.setProblemDefinition(pdef)
    pl.setup()

    anytime = name in ANYTIME
    has_best = hasattr(pl, "bestCost")
    t0 = time.perf_counter()
    first: list[float | None] = [None]
    over = [False]

    def solved() -> bool:
        if pdef.hasExactSolution():
            return True
        return has_best and math.isfinite(pl.bestCost().value())

    def stop() -> bool:
        now = time.perf_counter() - t0
        if first[0] is None and solved():
            first[0] = now
            if not anytime:
                return True
        if max_checks is not None and chk.checks > max_checks:
            over[0] = True
            return True
        return now >= time_limit

    if name in _THREADED:
        # Python conditions deadlock here (module doc): C++ timed slices, checks between.
        piece = min(max(0.02, time_limit / 50.0), time_limit)
        status = None
        while True:
            left = time_limit - (time.perf_counter() - t0)
            if left <= 1e-4:
                break
            status = pl.solve(ob.timedPlannerTerminationCondition(min(piece, left)))
            now = time.perf_counter() - t0
            if first[0] is None and pdef.hasExactSolution():
                first[0] = now
            if max_checks is not None and chk.checks > max_checks:
                over[0] = True
                break
    else:
        status = pl.solve(ob.PlannerTerminationCondition(stop))
    plan_secs = time.perf_counter() - t0
    exact = pdef.hasExactSolution() and not pdef.hasApproximateSolution()
    if exact and first[0] is None:
        first[0] = plan_secs  # planner returned at its first solution before we polled
    res: dict[str, Any] = {"status": str(status) if status is not None else "",
                           "time_to_first_solution": first[0] if exact else None}
    if not exact:
        if over[0]:
            why = f"cell-check budget {max_checks} exhausted"
        elif pdef.hasApproximateSolution():
            why = f"only an approximate solution within {time_limit:g} s"
        else:
            why = f"no solution within {time_limit:g} s"
        res.update(found=False, reason=why, seconds=plan_secs, cell_checks=chk.checks,
                   state_checks=chk.states, motion_checks=chk.motions,
                   checks_per_second=chk.checks / max(plan_secs, 1e-9))
        return res
    path = pdef.getSolutionPath()
    raw = _states(path)
    raw = _pin_ends(raw, s, g)
    simp = None
    if simplify:
        sp = og.PathGeometric(path)  # copy: the simplifier works in place
        ps = og.PathSimplifier(si)
        ps.simplify(sp, min(time_limit, 1.0))
        simp = _pin_ends(_states(sp), s, g)
    secs = time.perf_counter() - t0
    res.update(
        found=True, path_raw=raw, path=raw, path_simplified=simp, length_raw=_length(raw),
        length_simplified=_length(simp) if simp is not None else None,
        final_cost=_length(raw), cell_checks=chk.checks, seconds=secs,
        state_checks=chk.states, motion_checks=chk.motions,
        checks_per_second=chk.checks / max(secs, 1e-9), reason="",
    )
    return res


def _pin_ends(pts: list[list[float]], s: np.ndarray, g: np.ndarray) -> list[list[float]]:
    """Start first, goal last: snap end states within 1e-9 m, else add the point (the
    parent's re-validation covers any added segment)."""
    pts = [list(p) for p in pts]
    for end, idx in ((s, 0), (g, -1)):
        if pts and np.linalg.norm(np.subtract(pts[idx], end)) <= 1e-9:
            pts[idx] = [float(v) for v in end]
        elif idx == 0:
            pts.insert(0, [float(v) for v in end])
        else:
            pts.append([float(v) for v in end])
    return pts


def _warm() -> None:
    """Load (or compile) the kernels on a tiny world: dense and hash storage share types."""
    from planner.lattice import Lattice

    w = World(Lattice.named("cubic", cell_volume=1.0), np.array([[2, 2, 2]]),
              np.array([[0.0, 0.0, 0.0], [4.0, 4.0, 4.0]]))
    # Round trip: workers get unpickled (writable) arrays, another numba signature than
    # the read-only cached ones of a fresh lattice (the occupancy build kernels care).
    for x in (w, pickle.loads(pickle.dumps(w))):
        c = CompiledChecker(x, pickle.loads(pickle.dumps(lattice_tables(x.lattice))))
        c.point_free(0.3, 0.3, 0.3)
        c.segment_free((0.3, 0.3, 0.3), (3.4, 3.6, 3.5))


if os.environ.get(_WARM_ENV) == "1":  # pragma: no cover - runs inside the forkserver
    try:
        _warm()
    except Exception:  # a failed warm-up only costs time in the workers
        pass
