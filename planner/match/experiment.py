"""The paper's Fig. 6: scan-matching errors per lattice, from one command.

``planner match-experiment`` (or :func:`run_experiment`) matches every pair of
:mod:`planner.match.experiment_pairs` in every regime of
:mod:`planner.match.experiment_regimes` (by default: initial errors up to 0.5 m and 10
degrees) on every lattice at the same finest cell volume, and with the registration anchors
(:mod:`planner.match.anchor`, when the ``match`` extra is installed), all with the same
draws and the same scans. Each finished (regime, trial, method) row is appended to
``OUT/trials.jsonl`` at once, so a killed run loses no finished trial and ``--resume``
runs only the rest; the report
(:mod:`planner.match.experiment_report`) is then written: ``OUT/table.md``,
``OUT/summary.json``, ``OUT/trials.csv`` and the box plot (``OUT/fig6.png`` or ``--plot``).

Time per match is the process's CPU time, one thread: for the lattices, building the
reference's multi-resolution voxel list plus the match; for the anchors, their downsampling,
covariances and k-d trees plus the registration. Each method is run once on a small
cloud before any trial, so that compilation is never timed.
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
from planner.match.experiment_regimes import Regime, parse_regimes, regime_scans
from planner.match.matcher import match, pose_error
from planner.match.multires import MultiResVoxelList

__all__ = ["ROWS", "run_experiment", "read_rows", "trial_methods"]

ROWS = "trials.jsonl"
_CONFIG = "config.json"


def trial_methods(lattices: list[str], anchors: list[str] = ()) -> list[str]:
    """The methods of a run: the lattices (cubic first when present), then the anchors in
    :data:`planner.match.anchor.ANCHORS` order."""
    bad = [n for n in lattices if n not in NAMED_LATTICES]
    if bad or not lattices:
        raise PlannerError(f"unknown lattice {bad[0] if bad else '(none)'!r}: choose from "
                           f"{', '.join(NAMED_LATTICES)}")
    bad = [n for n in anchors if n not in anchor.ANCHORS]
    if bad:
        raise PlannerError(f"unknown anchor {bad[0]!r}: choose from "
                           f"{', '.join(anchor.ANCHORS)}")
    ordered = [n for n in NAMED_LATTICES if n in lattices]
    return ordered + [n for n in anchor.ANCHORS if n in anchors]


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
    t0 = time.process_time()
    res = match(src, MultiResVoxelList(ref, lattice, levels), init=init)
    return res.transform, time.process_time() - t0


def _run_one(method: str, src, ref, init, lattice: Lattice | None, levels: int):
    if lattice is None:
        return anchor.register(method, src, ref, init)
    return _lattice_match(src, ref, lattice, levels, init)


def _trial_row(pair: Pair, trial: Trial, method: str, lattice, levels: int,
               regime: Regime, seed: int) -> dict:
    r = trial.rotation[:3, :3]
    source, reference = regime_scans(regime, pair.source, pair.reference, pair.transform,
                                     seed, trial.pair, trial.index)
    src = np.ascontiguousarray(source @ r.T)
    ref = np.ascontiguousarray(reference @ r.T)
    levels += regime.extra_levels
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
    estimate = _conj(trial.rotation.T, fwd)  # back in the pair's own frames
    return {"trial": f"{regime.name}/{trial.key}", "regime": regime.name, "pair": pair.name,
            "group": pair.group, "kind": pair.kind, "index": trial.index, "method": method,
            "position_error": pos, "rotation_error": rot, "seconds": sec,
            "initial_position_error": e0[0], "initial_rotation_error": e0[1],
            "estimate": estimate.tolist(), "source_points": len(src),
            "reference_points": len(ref)}


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
                   anchors: list[str] | None = None, regimes=("default",), trials: int = 6,
                   cell_volume: float = 0.001, levels: int = 4, seed: int = 0,
                   max_offset: float = 0.5, max_angle: float = 10.0, resume: bool = False,
                   force: bool = False, progress: bool = True) -> list[dict]:
    """Run the Fig. 6 trials of every regime into ``out`` and return every finished row.

    Parameters
    ----------
    pairs : list of Pair
        From :func:`planner.match.experiment_pairs.load_sources` or ``user_pair``; names
        must be unique.
    out : path
        Output folder; ``trials.jsonl`` there grows one JSON row per (trial, method).
    lattices : sequence of str
        Named lattices, each scaled to ``cell_volume`` (m^3) at the finest level.
    anchors : list of str or None
        Registration anchors (:data:`planner.match.anchor.ANCHORS`) run too; None: all of
        them when the ``match`` extra is installed, none otherwise.
    regimes : sequence of str
        Regimes (:data:`planner.match.experiment_regimes.REGIMES`).
    trials : int
        Trials (rotation and initial error) per pair.
    levels : int
        Resolutions of the multi-resolution voxel lists.
    seed : int
        Seed of the shared draws.
    max_offset, max_angle : float
        Largest initial position (m) and rotation (degrees) error of the ``default``
        regime (the others have their own).
    resume, force : bool
        Continue the rows already in ``out``, or delete them and start again.
    progress : bool
        Progress with an ETA on stderr.

    Returns
    -------
    list of dict
        The rows: ``trial``, ``regime``, ``pair``, ``group``, ``kind``, ``method``,
        ``position_error`` (m), ``rotation_error`` (degrees), ``seconds`` (CPU per match),
        the initial errors, ``estimate`` (4x4 source -> reference in the pair's frames) and
        the points of each scan.

    Raises
    ------
    PlannerError
        Bad settings, anchors without the extra, or an ``out`` holding another run.
    """
    if anchors is None:
        anchors = list(anchor.ANCHORS) if anchor.available() else []
    methods = trial_methods(list(lattices), list(anchors))
    if anchors and not anchor.available():
        raise PlannerError(anchor.EXTRA_MESSAGE)
    if int(trials) != trials or trials < 1:
        raise PlannerError(f"trials must be a positive integer, got {trials!r}")
    if not (0 <= max_offset and 0 <= max_angle <= 180):
        raise PlannerError("initial errors need max_offset >= 0 and 0 <= max_angle <= 180")
    names = [p.name for p in pairs]
    if not pairs or len(set(names)) != len(names):
        raise PlannerError("the experiment needs at least one pair, with distinct names")
    regs = parse_regimes(list(regimes), max_offset, max_angle)
    config = {"pairs": names, "methods": methods, "cell_volume": cell_volume,
              "levels": levels, "seed": seed, "max_offset": max_offset,
              "max_angle": max_angle, "regimes": [r.name for r in regs]}
    out = Path(out)
    rows = _prepare_out(out, config, resume, force)
    done = {(r["trial"], r["method"]) for r in rows}
    lat = {m: Lattice.named(m, cell_volume) for m in methods if m in NAMED_LATTICES}
    todo = [(g, p, draw_trial(seed, i, k, g.max_offset, g.max_angle), m)
            for g in regs for i, p in enumerate(pairs) for k in range(trials)
            for m in methods]
    todo = [t for t in todo if (f"{t[0].name}/{t[2].key}", t[3]) not in done]
    if todo:
        _warm_up(methods, lat, todo[0][1], levels)
    bar = _Progress(sum(2 if p.kind == "consistency" else 1 for _, p, _, _ in todo),
                    progress)
    try:
        with open(out / ROWS, "a") as f:
            for regime, pair, trial, m in todo:
                row = _trial_row(pair, trial, m, lat.get(m), levels, regime, seed)
                f.write(json.dumps(row) + "\n")
                f.flush()
                rows.append(row)
                what = f"{regime.name} {pair.name} #{trial.index} {m}"
                bar.step(what)
                if pair.kind == "consistency":
                    bar.step(f"{what} back")
    finally:
        bar.close()
    keep = {(g.name, p.name, k) for g in regs for p in pairs for k in range(trials)}
    return [r for r in rows if (r.get("regime", "default"), r["pair"], r["index"]) in keep
            and r["method"] in methods]
