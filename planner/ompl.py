"""OMPL (PyPI ``ompl`` 2.0.1, nanobind bindings) as the continuous-space baseline.

The OMPL planners search ``RealVectorStateSpace(3)`` with the world's bounds on exactly the
same occupancy as the lattice planners. Both checks go through the world's one
:class:`planner.world.ValidityChecker`, the structs and kernels the lattice searches use:

* **State validity** (``checker.is_valid``): the lattice cell containing the state is in
  bounds and free. One compiled kernel quantizes the point (the exact generic closest-point
  kernel of :mod:`planner.lattice.quantize`) and does one occupancy lookup. One check.
* **Motion validity** (``checker.check_motion``): the 2.0.1 bindings let Python subclass
  ``ob.MotionValidator`` (``checkMotion(s1, s2)``), so motions are validated with the EXACT
  lattice segment walk (the lattice planners' line-of-sight test):
  a motion is valid iff every cell whose closed Voronoi cell the segment touches is free.
  Every cell looked at is counted. No interpolation resolution is involved, so no blocked
  cell can be skipped (a resolution-based check would need a step below the smallest
  distance a segment can travel inside a cell's corner, which is 0, so no finite step is
  exact). The longest-valid-segment fraction is therefore irrelevant and left at default.
  OMPL's ``checkMotion(s1, s2, lastValid)`` overload is not overridable from Python; the
  planners used here (and the path simplifier) call the two-state form.
* The parent process re-validates every returned segment with :meth:`World.segment_free`
  anyway (defence in depth: a path is never reported found unless that passes).

Process guard (:mod:`planner._guard`): OMPL runs in a worker process (``forkserver`` with
``ompl`` and this module preloaded and the checker kernels warmed up once) with a hard
timeout. A hang gives ``status="timeout"``; a worker killed by a signal or segfaulting
``status="crashed"`` with "worker crashed (signal N)"; the worker dies with its caller.

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
validity checker from the parent (rebuilding it means solving the lattice geometry's LPs
again).
"""

from __future__ import annotations

import math
import os
import pickle
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from planner._guard import run_guarded
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.path import path_length
from planner.world import ValidityChecker, World

__all__ = ["PLANNERS", "ANYTIME", "OmplResult", "plan_ompl", "run_seeds", "check_seed",
           "canonical_planner"]

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
_WARM_ENV = "PLANNER_OMPL_WARM"
_PRELOAD = ("numpy", "numba", "ompl.base", "ompl.geometric", "ompl.util", "planner.ompl")


# -- result ------------------------------------------------------------------------------
@dataclass
class OmplResult:
    """Outcome of one OMPL run (:func:`plan_ompl`).

    Attributes
    ----------
    found : bool
    path : ndarray, shape (K, 3)
        The raw path (m), start first, goal last; empty when not found.
    path_simplified : ndarray (K', 3) or None
        After ``og.PathSimplifier`` (None when not run or rejected).
    length_raw, length_simplified : float or None
        Path lengths (m).
    planner : str
        Canonical planner name.
    seed : int
    status : str
        ``"found"``, ``"no path"`` (time or check budget used up), ``"timeout"`` (worker
        killed at the hard limit), ``"crashed"`` (killed by a signal / exited without a
        result) or ``"error"`` (an exception in the worker).
    reason : str
        Why there is no path ("" when found).
    cell_checks, state_checks, motion_checks : int
        Occupancy lookups made in the worker, and the number of state / motion queries.
    seconds : float
        Planning + simplification wall time in the worker (s).
    wall_seconds : float
        Including the worker process (s).
    time_to_first_solution, final_cost : float or None
    valid_raw, valid_simplified : bool or None
        Re-validated here with :meth:`World.segment_free`.
    checks_per_second : float
    """

    found: bool
    planner: str
    seed: int
    path: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    path_simplified: np.ndarray | None = None
    length_raw: float | None = None
    length_simplified: float | None = None
    status: str = ""
    reason: str = ""
    cell_checks: int = 0
    state_checks: int = 0
    motion_checks: int = 0
    seconds: float = 0.0
    wall_seconds: float = 0.0
    time_to_first_solution: float | None = None
    final_cost: float | None = None
    valid_raw: bool | None = None
    valid_simplified: bool | None = None
    checks_per_second: float = 0.0

    @property
    def path_raw(self) -> np.ndarray:
        """The raw path (same as :attr:`path`)."""
        return self.path

    @property
    def length(self) -> float:
        """Length of the simplified path if any, else of the raw path (m; inf if none)."""
        if not self.found:
            return math.inf
        if self.length_simplified is not None:
            return self.length_simplified
        return self.length_raw if self.length_raw is not None else math.inf

    def to_dict(self) -> dict:
        """JSON-ready dict (paths as nested lists), with ``path_raw`` as well."""
        d = asdict(self)
        d["path"] = self.path.tolist()
        d["path_raw"] = d["path"]
        d["path_simplified"] = (None if self.path_simplified is None
                                else self.path_simplified.tolist())
        return d


# -- public API ----------------------------------------------------------------------------
def canonical_planner(name: str) -> str:
    """Canonical planner name; PlanError listing the valid ones if unknown."""
    key = str(name).strip().lower().replace("_", "")
    key = _ALIASES.get(key, key)
    if key not in PLANNERS:
        raise PlanError(f"unknown OMPL planner {name!r}; expected one of "
                        f"{', '.join(PLANNERS)}")
    return key


def _path_valid(world: World, path: np.ndarray) -> bool:
    p = np.asarray(path, dtype=float).reshape(-1, 3)
    if len(p) < 1 or not world.points_free(p[:1])[0]:
        return False
    return all(world.segment_free(p[i], p[i + 1]) for i in range(len(p) - 1))


SEED_LIMIT = 2**32


def check_seed(seed) -> int:
    """``seed`` as an int in [0, 2**32) (OMPL's RNG seed); PlanError otherwise."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not (
            0 <= seed < SEED_LIMIT):
        raise PlanError(f"seed must be an integer in [0, 2**32), got {seed!r}")
    return int(seed)


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
) -> OmplResult:
    """Plan with an OMPL planner on the world's validity checker, in a guarded worker.

    Parameters
    ----------
    world : World
    start, goal : array_like, shape (3,)
        Points (m, the map's frame); each must lie in a free cell (else PlanError,
        :meth:`World.endpoint`). The result's paths are in the map's frame too.
    planner : str
        A key of :data:`PLANNERS` (unknown names raise PlanError listing them).
    time_limit : float
        Planning budget (s). Anytime planners (:data:`ANYTIME`) use all of it; the others
        stop at the first solution.
    seed : int
        OMPL's global RNG seed (``ou.RNG.setSeed``) in the worker, in [0, 2**32).
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
    OmplResult
        A path is reported found only if every segment passes :meth:`World.segment_free`
        here as well.
    """
    name = canonical_planner(planner)
    seed = check_seed(seed)
    if isinstance(time_limit, bool) or not (isinstance(time_limit, int | float)
                                            and math.isfinite(time_limit) and time_limit > 0):
        raise PlanError(f"time_limit must be a positive number of seconds, got {time_limit!r}")
    s, _ = world.endpoint(start, "start")
    g, _ = world.endpoint(goal, "goal")
    hard = float(timeout) if timeout is not None else float(time_limit) + _EXTRA_TIMEOUT
    t0 = time.perf_counter()
    # Ship the checker (occupancy, walk and quantizer tables): the worker would otherwise
    # rederive the lattice geometry (LPs) that the parent has cached.
    out = run_guarded(_solve, (world.bounds, world.checker, s, g, name, float(time_limit),
                               seed, max_cell_checks, bool(simplify), bool(verbose)),
                      hard, _PRELOAD, _WARM_ENV)
    raw = np.asarray(out.pop("path_raw", None) or np.zeros((0, 3)), dtype=float).reshape(-1, 3)
    simp = out.pop("path_simplified", None)
    simp = None if simp is None else np.asarray(simp, dtype=float).reshape(-1, 3)
    out.pop("path", None)
    res = OmplResult(found=bool(out.pop("found", False)), planner=name, seed=seed, path=raw,
                     path_simplified=simp, **out)
    res.wall_seconds = time.perf_counter() - t0
    if res.found:
        res.valid_raw = _path_valid(world, raw)
        if not res.valid_raw:
            res.found, res.status = False, "invalid"
            res.reason = "raw path touched a blocked cell (rejected)"
        elif simp is not None:
            res.valid_simplified = _path_valid(world, simp)
            if not res.valid_simplified:
                res.path_simplified = res.length_simplified = None
                res.reason = "simplified path touched a blocked cell; kept raw path"
    if not res.found:
        res.path = np.zeros((0, 3))
        res.path_simplified = res.length_raw = res.length_simplified = None
        res.status = res.status if res.status not in ("", "found") else "no path"
    else:  # checked in the world's local frame; returned in the map's
        res.path = world.to_map(res.path)
        if res.path_simplified is not None:
            res.path_simplified = world.to_map(res.path_simplified)
    return res


def run_seeds(world: World, start, goal, seeds, **kw) -> list[OmplResult]:
    """:func:`plan_ompl` once per seed (same keyword arguments)."""
    return [plan_ompl(world, start, goal, seed=sd, **kw) for sd in seeds]


def _states(path) -> list[list[float]]:
    return [[float(st[0]), float(st[1]), float(st[2])] for st in path.getStates()]


def _solve(box, chk: ValidityChecker, s, g, name, time_limit, seed, max_checks, simplify,
           verbose) -> dict:
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_INFO if verbose else ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(int(seed))
    chk.is_valid(s)  # compile / load the kernels before the clock starts
    chk.check_motion(s, g)
    chk.checks = chk.states = chk.motions = 0

    space = ob.RealVectorStateSpace(3)
    bounds = ob.RealVectorBounds(3)
    lo, hi = box
    for i in range(3):
        bounds.setLow(i, float(lo[i]))  # bounds.low[i] = x edits a copy (silently lost)
        bounds.setHigh(i, float(hi[i]))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    si.setStateValidityChecker(lambda st: chk.is_valid((st[0], st[1], st[2])))

    class _Exact(ob.MotionValidator):
        def checkMotion(self, a, b):  # noqa: N802 - OMPL's name
            return chk.check_motion((a[0], a[1], a[2]), (b[0], b[1], b[2]))

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
        while True:
            left = time_limit - (time.perf_counter() - t0)
            if left <= 1e-4:
                break
            pl.solve(ob.timedPlannerTerminationCondition(min(piece, left)))
            now = time.perf_counter() - t0
            if first[0] is None and pdef.hasExactSolution():
                first[0] = now
            if max_checks is not None and chk.checks > max_checks:
                over[0] = True
                break
    else:
        pl.solve(ob.PlannerTerminationCondition(stop))
    plan_secs = time.perf_counter() - t0
    exact = pdef.hasExactSolution() and not pdef.hasApproximateSolution()
    if exact and first[0] is None:
        first[0] = plan_secs  # planner returned at its first solution before we polled
    res: dict[str, Any] = {"status": "found" if exact else "no path",
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
        found=True, path_raw=raw, path=raw, path_simplified=simp, length_raw=path_length(raw, 0.0),
        length_simplified=path_length(simp, 0.0) if simp is not None else None,
        final_cost=path_length(raw, 0.0), cell_checks=chk.checks, seconds=secs,
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
    """Load (or compile) the checker kernels on a tiny world, through a pickle round trip as
    the workers receive it."""
    w = World(Lattice.named("cubic", cell_volume=1.0), np.array([[2, 2, 2]]),
              np.array([[0.0, 0.0, 0.0], [4.0, 4.0, 4.0]]))
    c = pickle.loads(pickle.dumps(w.checker))
    c.is_valid((0.3, 0.3, 0.3))
    c.check_motion((0.3, 0.3, 0.3), (3.4, 3.6, 3.5))


if os.environ.get(_WARM_ENV) == "1":  # pragma: no cover - runs inside the forkserver
    try:
        _warm()
    except Exception:  # a failed warm-up only costs time in the workers
        pass
