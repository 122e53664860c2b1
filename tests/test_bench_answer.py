"""The answer a user reads: costs to the delivered path, queries each lattice cannot run,
checks and time disagreeing said first, and a decision table whose cells cite their rows;
all from hand-made rows whose answers are known."""

import numpy as np
import pytest

from planner.bench import paired, summary
from planner.bench.answer import decision_table, delivered_table, fair_queries_table, per_map_table


def _row(lat, q, *, checks, cpu, nb="full", meth="astar", rot=None, found=True,
         blocked=False, length=10.0, m="m"):
    return {"map": m, "cell_volume": 1.0, "radius": 0.0, "rotation": q % 8 if rot is None
            else rot, "query": q, "lattice": lat, "neighbors": nb, "method": meth, "seed": 0,
            "found": found, "blocked": blocked,
            "search_checks": 0.8 * checks, "smooth_checks": 0.2 * checks,
            "cell_checks": checks, "search_cpu_seconds": 0.9 * cpu,
            "smooth_cpu_seconds": 0.1 * cpu, "cpu_seconds": cpu, "seconds": cpu,
            "length": length if found else None,
            "length_smoothed": 0.9 * length if found else None}


def _fewer_checks_but_slower(n=40):
    """FCC: 0.7x cubic's checks on every query, 3x its CPU time."""
    rows = []
    for q in range(n):
        c = 1000.0 + 37 * q
        rows += [_row("cubic", q, checks=c, cpu=0.001 * (1 + q % 5)),
                 _row("fcc", q, checks=0.7 * c * (1 + 0.01 * (q % 3)),
                      cpu=0.003 * (1 + q % 5) * (1 + 0.01 * (q % 4)))]
    return rows


def test_checks_and_time_pointing_opposite_ways_open_the_comparison():
    _, prose = paired.paired_table(_fewer_checks_but_slower())
    assert prose[0].startswith("- **fcc full astar** vs cubic full astar: **Checks and CPU "
                               "time disagree: fcc full astar makes fewer cell checks than "
                               "cubic (0.7")
    assert "but takes more CPU time (3" in prose[0] and ".** It solved 100% of 40" in prose[0]
    assert "more CPU time to the delivered path" in prose[0]
    assert "fewer cell checks (search + smoothing)" in prose[0]


def test_the_delivered_table_shows_search_smoothing_and_their_sum():
    text = delivered_table(_fewer_checks_but_slower())
    cub, fcc = [ln for ln in text.splitlines() if ln.startswith(("| cubic", "| fcc"))]
    # cubic: median CPU 3 ms = 2.7 + 0.3; checks median of 1000 + 37 q, q < 40
    assert "| smoothed | 3 | 2.7 + 0.3 |" in cub
    med = float(np.median(1000.0 + 37 * np.arange(40)))
    assert f"| {med:,.0f} | {0.8 * med:,.0f} + {0.2 * med:,.0f} |" in cub
    cpu_ratio, checks_ratio = fcc.strip("| ").split(" | ")[-2:]
    assert cpu_ratio.startswith("3.0") and checks_ratio.startswith("0.70")


def test_a_lattice_that_blocks_an_end_fails_the_query_and_leaves_the_pairs():
    rows = _fewer_checks_but_slower()
    for r in rows:
        if r["lattice"] == "fcc" and r["query"] < 4:  # 4 of 40 endpoints blocked in FCC
            r.update(found=False, blocked=True, length=None, length_smoothed=None)
        if r["lattice"] == "cubic" and r["query"] == 5:  # cubic cannot connect one
            r.update(found=False, length=None, length_smoothed=None)
    record = {"g": {"map": "m", "kept": 40, "wanted": 40, "dropped": {
        "candidates free in some lattice": 200, "candidates blocked in fcc": 30,
        "candidates blocked in cubic": 10}}}
    text = fair_queries_table(rows, record)
    cub = next(ln for ln in text.splitlines() if "| cubic |" in ln)
    fcc = next(ln for ln in text.splitlines() if "| fcc |" in ln)
    assert cub == "| m | cubic | 40 | 0.0% | 5.0% | 2.5% |"
    assert fcc == "| m | fcc | 40 | 10.0% | 15.0% | 0.0% |"
    c = paired.compare_to_cubic(rows, "fcc", "full", "astar")
    assert c["common"] == 35  # the queries both lattices solved
    assert c["cell_checks"].n == 35
    assert c["success"]["cubic_only"] == 4 and c["success"]["x_only"] == 1


def test_fair_queries_table_skips_a_map_where_only_ompl_ran():
    """A map whose rows are all OMPL runs has no lattice search to count: the table leaves
    it out instead of failing (an OMPL-only suite's report)."""
    rows = [_row("cubic", q, checks=10.0, cpu=0.001, nb="-", meth="ompl:rrtstar", m="o")
            for q in range(4)]
    rows += [_row("cubic", q, checks=10.0, cpu=0.001) for q in range(4)]
    text = fair_queries_table(rows, {})
    assert "| m | cubic | 4 |" in text and "| o |" not in text


def test_the_decision_table_cites_the_rows_it_comes_from():
    rows = []
    for q in range(12):
        rows += [_row("cubic", q, checks=100.0, cpu=0.001, nb="face", length=12.0),
                 _row("bcc", q, checks=50.0, cpu=0.004, nb="face", length=10.0),
                 _row("bcc", q, checks=80.0, cpu=0.002, nb="full", length=11.0),
                 _row("cubic", q, checks=90.0, cpu=0.003, nb="full", length=11.0)]
    summary.add_ratios(rows)
    recs, table = per_map_table(rows, "m")
    assert [(r["row"], r["lattice"], r["neighbors"]) for r in recs] == [
        (1, "cubic", "face"), (2, "bcc", "face"), (3, "cubic", "full"), (4, "bcc", "full")]
    assert "| m-2 | bcc | face | astar | 100% | 12 | 4 | 50 | 1.0000 |" in table
    text, plain = decision_table(recs)
    assert ("| m | bcc face astar (m-2: 50 checks) | cubic face astar (m-1: 1 ms CPU) | "
            "bcc face astar (m-2: 1.0000 of best) |") in text
    assert plain == ["On m, cubic delivers the fastest plan (face astar, row m-1, 1 ms median "
                     "CPU); the fastest other lattice, bcc full astar (row m-4), takes 2 ms."]


def test_a_winner_that_fails_queries_says_so():
    rows = []
    for q in range(10):
        rows += [_row("cubic", q, checks=100.0, cpu=0.001),
                 _row("fcc", q, checks=50.0, cpu=0.002, found=q > 0)]
    summary.add_ratios(rows)
    text, _ = decision_table(per_map_table(rows, "m")[0])
    assert "fcc full astar (m-2: 50 checks; solved 90%, best 100%)" in text


@pytest.mark.slow
def test_queries_are_kept_where_one_lattice_can_run_them():
    from planner import build_world
    from planner.bench.queries import sample_queries

    # a slab of points; at this coarse cell volume FCC and cubic block different cells
    rng = np.random.default_rng(0)
    pts = rng.uniform([0, 0, 0], [4, 4, 1], (400, 3))
    box = np.array([[0.0, 0.0, 0.0], [4.0, 4.0, 1.0]])
    worlds = {lat: build_world(pts, lat, cell_volume=0.02, radius=0.05, bounds=box)
              for lat in ("cubic", "fcc")}
    s, g, info = sample_queries(worlds, box, 12, seed=1, min_distance=0.2, neighbors=None)
    assert len(s) == 12
    free = {k: w.points_free(s) & w.points_free(g) for k, w in worlds.items()}
    assert np.all(free["cubic"] | free["fcc"])  # every pair runs on some lattice
    for k in worlds:  # and the record counts the kept pairs each lattice blocks
        assert info[f"kept but blocked in {k}"] == int(np.sum(~free[k]))
        assert 0 <= info[f"candidates blocked in {k}"] <= info["candidates free in some lattice"]
    assert sum(info[f"kept but blocked in {k}"] for k in worlds) > 0
