"""Paired lattice-vs-cubic statistics: intervals cover, tests reject only real differences."""

import math

import numpy as np
import pytest

from planner.analysis.stats import describe, paired_ratio


def test_interval_contains_the_median_and_shrinks_with_more_queries():
    rng = np.random.default_rng(3)
    y = rng.uniform(50, 500, size=400)
    x = y * rng.lognormal(mean=np.log(0.6), sigma=0.2, size=400)
    small = paired_ratio(x[:40], y[:40])
    large = paired_ratio(x, y)
    for s in (small, large):
        assert s.low <= s.median <= s.high
    assert (large.high - large.low) < (small.high - small.low)
    assert 0.55 < large.median < 0.65
    assert large.low < 0.6 < large.high


def test_identical_samples_are_no_difference():
    y = np.arange(1.0, 31.0)
    s = paired_ratio(y, y)
    assert s.median == 1.0 and s.low == 1.0 and s.high == 1.0
    assert not s.significant()
    assert describe(s, "checks").startswith("no significant difference in checks")


@pytest.mark.parametrize("x", [[2.0], [2.0, 3.0], [1.5] * 12, [1.0] * 40 + [0.9, 1.2, 1.1]],
                         ids=["one", "two", "all-equal", "ties"])
def test_degenerate_samples_give_a_definite_interval_without_warnings(x):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = paired_ratio(np.array(x), np.ones(len(x)))
    assert s.n == len(x) and math.isfinite(s.low) and math.isfinite(s.high)
    assert min(x) <= s.low <= s.median <= s.high <= max(x)
    if len(set(x)) == 1 or len(x) == 43:  # every resample has the same median
        assert s.low == s.high == s.median


def test_the_interval_is_seeded():
    rng = np.random.default_rng(4)
    y = rng.uniform(1, 2, size=50)
    x = y * rng.lognormal(0.0, 0.3, size=50)
    a, b, c = paired_ratio(x, y, seed=3), paired_ratio(x, y, seed=3), paired_ratio(x, y, seed=4)
    assert (a.low, a.high) == (b.low, b.high) and (a.low, a.high) != (c.low, c.high)


def test_the_95_percent_interval_covers_the_true_median_about_95_percent_of_the_time():
    rng = np.random.default_rng(11)
    true = math.exp(-0.5)  # median of the lognormal ratios drawn below
    covered = 0
    for trial in range(120):
        y = rng.uniform(10, 100, size=30)
        x = y * rng.lognormal(-0.5, 0.4, size=30)
        s = paired_ratio(x, y, n_boot=1999, seed=trial)
        covered += s.low <= true <= s.high
    assert 0.85 <= covered / 120 <= 1.0 and covered < 120


def test_noise_around_one_is_not_significant():
    rng = np.random.default_rng(7)
    y = rng.uniform(10, 20, size=30)
    x = y * rng.lognormal(0.0, 0.05, size=30)
    s = paired_ratio(x, y)
    assert s.p > 0.05
    assert describe(s, "length").startswith("no significant difference")


def test_failed_queries_are_left_out_of_the_pairs():
    x = np.array([1.0, 2.0, math.nan, 4.0, 0.0])
    y = np.array([2.0, 4.0, 6.0, math.inf, 5.0])
    s = paired_ratio(x, y)
    assert s.n == 2 and s.median == 0.5


def test_sentence_says_direction_interval_and_p():
    rng = np.random.default_rng(1)
    y = rng.uniform(100, 200, size=80)
    s = paired_ratio(1.3 * y * rng.uniform(0.95, 1.05, 80), y)
    text = describe(s, "checks", less="fewer", more="more")
    assert text.startswith("more checks (median 1.")
    assert "95% CI" in text and "p < 0.001" in text and "n = 80" in text


def test_rotation_samples_are_uniform_and_shared():
    from scipy.spatial.transform import Rotation

    from planner.bench.rotations import sample_rotations

    def quaternion_matrix(q):  # the order is scipy's and ROS's: x, y, z, w
        return Rotation.from_quat(q).as_matrix()

    a = sample_rotations("so3", 2000, seed=5)
    assert np.array_equal(a, sample_rotations("so3", 2000, seed=5))  # same for every lattice
    z = np.array([quaternion_matrix(q)[:, 2] for q in a])  # image of the z axis
    # Uniform rotations send z to a uniform direction: each coordinate has mean 0, var 1/3.
    assert np.all(np.abs(z.mean(axis=0)) < 0.05)
    assert np.all(np.abs(z.var(axis=0) - 1 / 3) < 0.03)
    yaw = np.array([quaternion_matrix(q) for q in sample_rotations("yaw", 50, seed=2)])
    assert np.allclose(yaw[:, 2], [0, 0, 1]) and np.allclose(yaw[:, :, 2], [0, 0, 1])
    assert np.all(a[:, 3] >= 0) and np.allclose(np.linalg.norm(a, axis=1), 1)
    # x, y, z, w: a turn about z has x = y = 0 (in w, x, y, z order it would be y = z = 0).
    q = sample_rotations("yaw", 5, seed=2)
    assert np.allclose(q[:, :2], 0) and not np.allclose(q[:, 2], 0)


def test_the_readme_results_are_spliced_from_the_run(tmp_path):
    from planner.analysis.readme_results import END, START, update_readme
    from planner.errors import PlannerError

    run = tmp_path / "results" / "full"
    run.mkdir(parents=True)
    (run / "results_section.md").write_text("fewer checks (median 0.59)\n\n![pareto](pareto.png)\n")
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n\n{START}\nstale numbers\n{END}\n\nmore\n")
    update_readme(run, readme)
    text = readme.read_text()
    assert "stale" not in text and "fewer checks (median 0.59)" in text
    assert "![pareto](results/full/pareto.png)" in text
    assert text.startswith("# title") and text.endswith("more\n")
    readme.write_text("no markers")
    with pytest.raises(PlannerError, match="markers"):
        update_readme(run, readme)  # an existing page without markers is never overwritten
    page = tmp_path / "benchmarks" / "results.md"
    page.parent.mkdir()
    update_readme(run, page)  # a new page of its own
    assert "fewer checks (median 0.59)" in page.read_text()
    assert "![pareto](../results/full/pareto.png)" in page.read_text()
