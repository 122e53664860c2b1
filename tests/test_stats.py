"""Paired lattice-vs-cubic statistics: one estimate, an interval and a p-value that cannot
disagree, checked by hand on small samples; no verdict from too few queries."""

import math

import numpy as np
import pytest

from planner.analysis.stats import (
    describe,
    disagreement,
    hodges_lehmann,
    paired_ratio,
    signed_rank_cdf,
    walsh_averages,
)

# Ten log ratios without ties: ranks of |d| are 1..10 in this order of magnitude.
HAND = np.array([-0.9, -0.7, -0.5, -0.3, -0.1, 0.2, 0.4, 0.6, 0.8, 1.0]) / 10


def test_hand_checked_signed_rank_interval_and_p():
    # Positive d have |d| ranks 2, 4, 6, 8, 10: T+ = 30, T- = 25. Tables: n = 10, the
    # two-sided 5% critical value of T is 8, so the interval is the 9th smallest and 9th
    # largest of the 55 Walsh averages.
    s = paired_ratio(np.exp(HAND), np.ones(10))
    w = walsh_averages(HAND)
    assert len(w) == 55
    assert s.low == pytest.approx(math.exp(w[8])) and s.high == pytest.approx(math.exp(w[-9]))
    assert s.estimate == pytest.approx(math.exp(np.median(w)))
    # exact two-sided p = 2 P(T <= 25) for n = 10 (the table's 1024 sign patterns)
    cdf = signed_rank_cdf(10)
    assert cdf[8] <= 0.025 < cdf[9]
    assert s.p == pytest.approx(2 * cdf[25])
    from scipy.stats import wilcoxon

    assert s.p == pytest.approx(wilcoxon(HAND, method="exact").pvalue)
    assert s.verdict() == "same" and s.low < 1 < s.high


def test_the_null_distribution_counts_sign_patterns():
    # n = 3: the 8 sign patterns give T = 0, 1, 2, 3, 3, 4, 5, 6
    assert np.allclose(signed_rank_cdf(3) * 8, [1, 2, 3, 5, 6, 7, 8])
    assert signed_rank_cdf(12)[-1] == pytest.approx(1.0)


def test_hodges_lehmann_is_the_median_of_walsh_averages():
    assert hodges_lehmann(np.array([0.0, 1.0, 5.0])) == 1.75  # 0 .5 1 | 2.5 3 5
    assert hodges_lehmann(np.array([2.0])) == 2.0


def test_all_ratios_one_half_is_fewer_with_p_two_in_1024():
    x = np.arange(5.0, 15.0)
    s = paired_ratio(x, 2 * x)
    assert s.estimate == pytest.approx(0.5) and s.low == pytest.approx(0.5)
    assert s.p == pytest.approx(2 / 1024) and s.verdict() == "lower"
    assert describe(s, "checks", less="fewer", more="more").startswith(
        "fewer checks (Hodges-Lehmann ratio 0.5 [0.5, 0.5], p = 0.002, n = 10)")


@pytest.mark.parametrize("clustered", [False, True], ids=["wilcoxon", "cluster"])
def test_the_interval_excludes_one_exactly_when_p_is_small(clustered):
    """The sentence of issue 45 ("more checks (median 1.04, CI ..., p = 0.014)" where the
    test said fewer) cannot happen: direction, interval and p come from one statistic."""
    rng = np.random.default_rng(2)
    seen = set()
    for trial in range(60):
        n = int(rng.integers(10, 40))
        y = rng.uniform(1, 2, n)
        x = y * rng.lognormal(rng.normal(0, 0.15), 0.3, n)
        tie = rng.random(n) < 0.2
        x[tie] = y[tie]  # exact ties at ratio 1
        labels = rng.integers(0, 8, n) if clustered else None
        s = paired_ratio(x, y, clusters=labels, n_boot=400, seed=trial)
        excludes = s.high < 1 or s.low > 1
        assert excludes == (s.p <= 0.05), s
        assert s.low <= s.estimate <= s.high or clustered
        v = s.verdict()
        seen.add(v)
        assert v == ("same" if not excludes else "lower" if s.high < 1 else "higher")
        if v == "lower":
            assert s.estimate < 1 or clustered
    assert {"lower", "same"} <= seen


def test_few_queries_give_no_verdict():
    x = np.array([1.0, 2.0, 3.0, 4.0])
    s = paired_ratio(0.5 * x, x)  # every ratio 0.5, but only 4 queries
    assert s.verdict() == "too few"
    assert describe(s, "checks").startswith("too few queries to compare checks")
    assert "n = 4" in describe(s, "checks")


def test_pooled_groups_widen_the_interval_and_few_groups_give_no_verdict():
    # 4 groups of 10 identical queries each: 40 pairs, but 4 independent observations
    d = np.repeat([-0.3, -0.2, -0.1, 0.05], 10)
    ones = np.ones(40)
    alone = paired_ratio(np.exp(d), ones)
    pooled = paired_ratio(np.exp(d), ones, clusters=np.repeat(list("abcd"), 10))
    assert alone.verdict() == "lower"
    assert pooled.method == "cluster bootstrap" and pooled.clusters == 4
    assert pooled.verdict() == "too few"
    assert describe(pooled, "time").startswith("too few groups to compare time")
    six = paired_ratio(np.exp(np.repeat([-0.3, -0.2, -0.1, 0.05, 0.3, 0.2], 10)),
                       np.ones(60), clusters=np.repeat(list("abcdef"), 10))
    assert six.high - six.low > 0 and six.verdict() == "same"


def test_the_cluster_bootstrap_resamples_whole_groups():
    """The weighted shortcut gives the estimates of the resamples built by hand."""
    from planner.analysis.stats import _cluster_bootstrap

    rng = np.random.default_rng(5)
    d = np.round(rng.normal(size=25), 1)  # ties too
    lab = rng.integers(0, 6, 25)
    low, high, p = _cluster_bootstrap(d, lab, 200, 0.95, 3)
    _, inv = np.unique(lab, return_inverse=True)
    groups = [np.flatnonzero(inv == g) for g in range(inv.max() + 1)]
    picks = np.random.default_rng(3).integers(0, len(groups), size=(200, len(groups)))
    boot = np.sort([hodges_lehmann(d[np.concatenate([groups[g] for g in pick])])
                    for pick in picks])
    assert (low, high) == pytest.approx((boot[5], boot[194]))
    assert p == pytest.approx(min(1, 2 * min(np.sum(boot <= 0), np.sum(boot >= 0)) / 200))


def test_checks_and_time_pointing_opposite_ways_are_said_in_one_sentence():
    x = np.arange(10.0, 30.0)
    fewer = paired_ratio(0.7 * x, x)
    slower = paired_ratio(3.0 * x, x)
    text = disagreement(fewer, slower, "fcc face lazy-theta")
    assert text == ("Checks and time disagree: fcc face lazy-theta makes fewer cell checks "
                    "than cubic (0.7x [0.7, 0.7]) but takes more time (3x [3, 3]).")
    assert disagreement(fewer, paired_ratio(0.5 * x, x), "x") is None
    assert disagreement(fewer, paired_ratio(x, x), "x") is None


def test_identical_samples_are_no_difference():
    y = np.arange(1.0, 31.0)
    s = paired_ratio(y, y)
    assert s.estimate == 1.0 and s.low == 1.0 and s.high == 1.0
    assert not s.significant()
    assert describe(s, "checks").startswith("no clear difference in checks")


@pytest.mark.parametrize("x", [[2.0], [2.0, 3.0], [1.5] * 12, [1.0] * 40 + [0.9, 1.2, 1.1]],
                         ids=["one", "two", "all-equal", "ties"])
def test_degenerate_samples_give_a_definite_answer_without_warnings(x):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = paired_ratio(np.array(x), np.ones(len(x)))
    assert s.n == len(x) and s.low <= s.estimate <= s.high
    if len(x) < 6:  # no interval at 95% exists from so few signs
        assert s.low == 0 and s.high == math.inf and s.verdict() == "too few"


def test_the_95_percent_interval_covers_the_true_ratio_about_95_percent_of_the_time():
    rng = np.random.default_rng(11)
    true = math.exp(-0.5)  # centre of the symmetric log ratios drawn below
    covered = 0
    for _ in range(200):
        y = rng.uniform(10, 100, size=30)
        x = y * rng.lognormal(-0.5, 0.4, size=30)
        s = paired_ratio(x, y)
        covered += s.low <= true <= s.high
    assert 0.9 <= covered / 200 <= 0.99


def test_noise_around_one_is_not_significant():
    rng = np.random.default_rng(7)
    y = rng.uniform(10, 20, size=30)
    x = y * rng.lognormal(0.0, 0.05, size=30)
    s = paired_ratio(x, y)
    assert s.p > 0.05
    assert describe(s, "length").startswith("no clear difference")


def test_failed_queries_are_left_out_of_the_pairs():
    x = np.array([1.0, 2.0, math.nan, 4.0, 0.0])
    y = np.array([2.0, 4.0, 6.0, math.inf, 5.0])
    s = paired_ratio(x, y)
    assert s.n == 2 and s.estimate == 0.5


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
