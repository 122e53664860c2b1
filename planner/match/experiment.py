"""The paper's Fig. 6: scan-matching errors per lattice, from one command.

``planner match-experiment`` (or :func:`run_experiment`) matches every pair of
:mod:`planner.match.experiment_pairs` from many random initial errors (up to 0.5 m and 10
degrees) on every lattice at the same finest cell volume, and with the ICP anchor
(:mod:`planner.match.anchor`, when the ``match`` extra is installed), all with the same
draws. Each finished (trial, method) row is appended to ``OUT/trials.jsonl`` at once, so a
killed run loses no finished trial and ``--resume`` runs only the rest; the report
(:mod:`planner.match.experiment_report`) is then written: ``OUT/table.md``,
``OUT/summary.json``, ``OUT/trials.csv`` and the box plot (``OUT/fig6.png`` or ``--plot``).

Time per match is wall time on one thread: for the lattices, building the reference's
multi-resolution voxel list plus the match; for ICP, its downsampling, normals and k-d tree
plus the registration. Each method is run once on a small cloud before any trial, so that
compilation is never timed.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from planner.errors import PlannerError
from planner.fsutil import write_text_atomic
from planner.lattice import NAMED_LATTICES, Lattice
from planner.match import anchor
from planner.match.experiment_pairs import Pair, Trial, draw_trial
from planner.match.matcher import match, pose_error
from planner.match.multires import MultiResVoxelList

__all__ = ["ROWS", "run_experiment", "read_rows", "trial_methods"]

ROWS = "trials.jsonl"
_CONFIG = "config.json"


def trial_methods(lattices: list[str], icp: bool) -> list[str]:
    """The methods of a run: the lattices (cubic first when present), then ``icp``."""
    bad = [n for n in lattices if n not in NAMED_LATTICES]
    if bad or not lattices:
        raise PlannerError(f"unknown lattice {bad[0] if bad else '(none)'!r}: choose from "
                           f"{', '.join(NAMED_LATTICES)}")
    ordered = [n for n in NAMED_LATTICES if n in lattices]
    return ordered + (["icp"] if icp else [])


def read_rows(path: str | Path) -> list[dict]:
    """The finished rows of ``OUT/trials.jsonl`` (a line cut by a kill is ignored)."""
    p = Path(path)
    if not p.is_file():
        return []
    rows = []
    for line in p.read_text().splitlines():
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            continue  # the unfinished last line of a killed run
    return rows


class _Progress:
    """Progress on stderr with an ETA: redrawn on a terminal, a line per ~10% otherwise."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.done, self.t0 = total, 0, time.perf_counter()
        self.enabled = enabled and total > 0
        self.tty = self.enabled and sys.stderr.isatty()
        self.next_tenth = 1

    def step(self, what: str) -> None:
        self.done += 1
        if not self.enabled:
            return
        el = time.perf_counter() - self.t0
        frac = self.done / self.total
        text = (f"{self.done}/{self.total} matches  {el:5.0f} s  eta {el / frac - el:4.0f} s"
                f"  ({what})")
        if self.tty:
            print(f"\r{text:<78}", end="", file=sys.stderr, flush=True)
        elif frac * 10 >= self.next_tenth:
            self.next_tenth = int(frac * 10) + 1
            print(f"progress {frac:4.0%}: {text}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.tty:
            print(file=sys.stderr)


def _conj(rot: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``m`` expressed after both clouds are rotated by ``rot``: R m R^-1."""
    return rot @ m @ rot.T


def _lattice_match(src, ref, lattice: Lattice, levels: int, init) -> tuple[np.ndarray, float]:
    t0 = time.perf_counter()
    res = match(src, MultiResVoxelList(ref, lattice, levels), init=init)
    return res.transform, time.perf_counter() - t0


def _run_one(method: str, src, ref, init, lattice: Lattice | None, levels: int):
    if method == "icp":
        return anchor.icp(src, ref, init)
    return _lattice_match(src, ref, lattice, levels, init)


def _trial_row(pair: Pair, trial: Trial, method: str, lattice, levels: int) -> dict:
    r = trial.rotation[:3, :3]
    src = np.ascontiguousarray(pair.source @ r.T)
    ref = np.ascontiguousarray(pair.reference @ r.T)
    known = _conj(trial.rotation, pair.transform)
    init = trial.error @ known
    e0 = pose_error(init, known)
    fwd, sec = _run_one(method, src, ref, init, lattice, levels)
    if pair.kind == "truth":
        pos, rot = pose_error(fwd, known)
    else:  # B->A from the inverse of A->B's start: the composition should be the identity
        back, sec_b = _run_one(method, ref, src, np.linalg.inv(init), lattice, levels)
        pos, rot = pose_error(back @ fwd, np.eye(4))
        sec = (sec + sec_b) / 2
    return {"trial": trial.key, "pair": pair.name, "group": pair.group, "kind": pair.kind,
            "index": trial.index, "method": method, "position_error": pos,
            "rotation_error": rot, "seconds": sec, "initial_position_error": e0[0],
            "initial_rotation_error": e0[1]}


def _warm_up(methods: list[str], lattices: dict, pair: Pair, levels: int) -> None:
    """One untimed match per method on a small cloud: compiles (or loads) the kernels."""
    k = max(1, len(pair.source) // 3000)
    src, ref = pair.source[::k], pair.reference[::k]
    for m in methods:
        _run_one(m, src, ref, pair.transform, lattices.get(m), levels)


def _prepare_out(out: Path, config: dict, resume: bool, force: bool) -> list[dict]:
    """Check ``out`` against the run's settings; the rows already finished there."""
    rows_path, cfg_path = out / ROWS, out / _CONFIG
    if force and rows_path.exists():
        rows_path.unlink()
    rows = read_rows(rows_path)
    if rows and not resume:
        raise PlannerError(f"{out} already holds {len(rows)} finished rows: --resume to "
                           f"continue them or --force to start again")
    if rows and cfg_path.is_file():
        old = json.loads(cfg_path.read_text())
        diff = sorted(k for k in config if old.get(k) != config[k])
        if diff:
            raise PlannerError(f"{out} holds a run with other settings ({', '.join(diff)}): "
                               f"use another --out, or --force to start again")
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(cfg_path, json.dumps(config, indent=1))
    if rows_path.is_file():  # cut a line left unfinished by a kill
        data = rows_path.read_bytes()
        if data and not data.endswith(b"\n"):
            rows_path.write_bytes(data[:data.rfind(b"\n") + 1])
    return rows


def run_experiment(pairs: list[Pair], out: str | Path, *, lattices=NAMED_LATTICES,
                   icp: bool | None = None, trials: int = 6, cell_volume: float = 0.001,
                   levels: int = 4, seed: int = 0, max_offset: float = 0.5,
                   max_angle: float = 10.0, resume: bool = False, force: bool = False,
                   progress: bool = True) -> list[dict]:
    """Run the Fig. 6 trials into ``out`` and return every finished row.

    Parameters
    ----------
    pairs : list of Pair
        From :func:`planner.match.experiment_pairs.load_sources` or ``user_pair``; names
        must be unique.
    out : path
        Output folder; ``trials.jsonl`` there grows one JSON row per (trial, method).
    lattices : sequence of str
        Named lattices, each scaled to ``cell_volume`` (m^3) at the finest level.
    icp : bool or None
        Run the ICP anchor too; None: when the ``match`` extra is installed.
    trials : int
        Trials (rotation and initial error) per pair.
    levels : int
        Resolutions of the multi-resolution voxel lists.
    seed : int
        Seed of the shared draws.
    max_offset, max_angle : float
        Largest initial position (m) and rotation (degrees) error.
    resume, force : bool
        Continue the rows already in ``out``, or delete them and start again.
    progress : bool
        Progress with an ETA on stderr.

    Returns
    -------
    list of dict
        The rows: ``trial``, ``pair``, ``group``, ``kind``, ``method``,
        ``position_error`` (m), ``rotation_error`` (degrees), ``seconds`` (per match), the
        initial errors.

    Raises
    ------
    PlannerError
        Bad settings, an ICP run without the extra, or an ``out`` holding another run.
    """
    if icp is None:
        icp = anchor.available()
    elif icp and not anchor.available():
        raise PlannerError(anchor.EXTRA_MESSAGE)
    methods = trial_methods(list(lattices), icp)
    if int(trials) != trials or trials < 1:
        raise PlannerError(f"trials must be a positive integer, got {trials!r}")
    if not (0 <= max_offset and 0 <= max_angle <= 180):
        raise PlannerError("initial errors need max_offset >= 0 and 0 <= max_angle <= 180")
    names = [p.name for p in pairs]
    if not pairs or len(set(names)) != len(names):
        raise PlannerError("the experiment needs at least one pair, with distinct names")
    config = {"pairs": names, "methods": methods, "cell_volume": cell_volume,
              "levels": levels, "seed": seed, "max_offset": max_offset,
              "max_angle": max_angle}
    out = Path(out)
    rows = _prepare_out(out, config, resume, force)
    done = {(r["trial"], r["method"]) for r in rows}
    lat = {m: Lattice.named(m, cell_volume) for m in methods if m != "icp"}
    todo = [(p, draw_trial(seed, i, k, max_offset, max_angle), m)
            for i, p in enumerate(pairs) for k in range(trials) for m in methods]
    todo = [t for t in todo if (t[1].key, t[2]) not in done]
    if todo:
        _warm_up(methods, lat, todo[0][0], levels)
    bar = _Progress(sum(2 if p.kind == "consistency" else 1 for p, _, _ in todo), progress)
    try:
        with open(out / ROWS, "a") as f:
            for pair, trial, m in todo:
                row = _trial_row(pair, trial, m, lat.get(m), levels)
                f.write(json.dumps(row) + "\n")
                f.flush()
                rows.append(row)
                bar.step(f"{pair.name} #{trial.index} {m}")
                if pair.kind == "consistency":
                    bar.step(f"{pair.name} #{trial.index} {m} back")
    finally:
        bar.close()
    keep = {(p.name, k) for p in pairs for k in range(trials)}
    return [r for r in rows if (r["pair"], r["index"]) in keep and r["method"] in methods]
