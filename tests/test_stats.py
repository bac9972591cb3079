"""Intervals that cover, paired sensitivities, and the paper's estimation-error curve, on hand-built results."""

import numpy as np
import pandas as pd
import pytest
from scipy.stats import beta

from lerobot_contrast import stats
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.trial import TrialRecord

STUDIES = 1000


def table(rows):
    """A results table from (base_id, perturbation, status, success, spl, cost) tuples, in trial order."""
    df = pd.DataFrame(rows, columns=["base_id", "perturbation", "status", "success", "spl", "cost"])
    df["index"] = np.arange(len(df))
    df["cumulative_cost"] = df["cost"].cumsum()
    df["instance_id"] = [b if p is None else f"{b}/{p}" for b, p in zip(df["base_id"], df["perturbation"], strict=True)]
    df["repeat"] = 0
    df["family"] = "push"
    df["progress"] = df["success"].astype("float64")
    return df


def simulated_study(rng, n_bases, binary):
    """One contrast-style study: each base has 1 to 5 trials sharing a base-level success probability."""
    p = rng.beta(3.0, 2.0, size=n_bases)  # true mean 0.6
    sizes = rng.integers(1, 6, size=n_bases)
    clusters = np.repeat(np.arange(n_bases), sizes)
    if binary:
        values = (rng.random(len(clusters)) < p[clusters]).astype(float)
    else:  # SPL-like: success times a path efficiency with mean 0.8
        values = (rng.random(len(clusters)) < p[clusters]) * rng.beta(8.0, 2.0, size=len(clusters))
    return values, clusters


@pytest.mark.parametrize(("binary", "truth"), [(True, 0.6), (False, 0.6 * 0.8)])
@pytest.mark.parametrize("n_bases", [30, 100])
def test_clustered_95_percent_intervals_cover_a_known_mean_without_being_needlessly_wide(binary, truth, n_bases):
    """Binary outcomes cover close to 95%; SPL-like ones more (the interval bounds their variance by a
    Bernoulli variable's, see korn_graubard)."""
    rng = np.random.default_rng(2024)
    covered = 0
    for _ in range(STUDIES):
        values, clusters = simulated_study(rng, n_bases, binary)
        e = stats.estimate(values, clusters)
        covered += e.low <= truth <= e.high
    assert 0.94 <= covered / STUDIES <= (0.97 if binary else 0.99), covered / STUDIES


def test_the_fixed_n_interval_is_clopper_pearson_for_independent_trials_and_widens_for_clusters():
    independent = stats.estimate(np.array([1, 1, 1, 0, 1, 0, 1, 1, 1, 1.0]), np.arange(10))
    assert independent.method == "korn_graubard"
    # v = 10/9 * 1.6 / 100, so n* = 0.16 / v = 9 and 7.2 "successes": Clopper-Pearson's beta quantiles
    expected = (beta.ppf(0.025, 7.2, 9 - 7.2 + 1), beta.ppf(0.975, 7.2 + 1, 9 - 7.2))
    assert (independent.low, independent.high) == pytest.approx(expected, abs=1e-9)
    eight_of_ten = stats.estimate(np.array([1.0] * 8 + [0.0] * 2), np.arange(10))
    assert eight_of_ten.low == pytest.approx(independent.low)
    values = np.array([1, 1, 0, 0, 1, 1, 0, 0.0])
    clustered = stats.estimate(values, np.array([0, 0, 1, 1, 2, 2, 3, 3]))
    spread = stats.estimate(values, np.arange(8))
    assert clustered.n_clusters == 4 and clustered.high - clustered.low > spread.high - spread.low
    all_pass = stats.estimate(np.ones(12), np.repeat(np.arange(4), 3))
    # every outcome equal: each base counts once, n* = 4, and Clopper-Pearson's low is 0.025^(1/4)
    assert all_pass.high == 1.0 and all_pass.low == pytest.approx(0.025 ** (1 / 4))


def test_all_successes_over_few_bases_count_each_base_once():
    """5 of 5 over 3 bases read [0.052, 1.000] when the degrees-of-freedom factor also shrank n* = 3 to 1.25."""
    five = stats.estimate(np.ones(5), np.array([0, 0, 1, 1, 2]))
    assert (round(five.low, 3), five.high) == (0.292, 1.0)
    none = stats.estimate(np.zeros(5), np.array([0, 0, 1, 1, 2]))
    assert (none.low, round(none.high, 3)) == (0.0, 0.708)
    # Bases whose trials share one outcome are the worst case: the interval still covers 95% of studies.
    rng, covered = np.random.default_rng(3), 0
    for _ in range(STUDIES):
        sizes = rng.integers(1, 6, size=3)
        outcomes = np.repeat(rng.random(3) < 0.4, sizes).astype(float)
        e = stats.estimate(outcomes, np.repeat(np.arange(3), sizes))
        covered += e.low <= 0.4 <= e.high
    assert covered / STUDIES >= 0.95, covered / STUDIES


@pytest.mark.parametrize("n_bases", [10, 30, 100])
@pytest.mark.parametrize("rate", [0.03, 0.97])
def test_the_fixed_n_interval_covers_rare_and_common_outcomes(n_bases, rate):
    """The edges where the cluster bootstrap covered about 91%: heterogeneous bases of 1 to 10 trials."""
    rng = np.random.default_rng(7)
    covered = 0
    for _ in range(STUDIES):
        p = rng.beta(5 * rate, 5 * (1 - rate), size=n_bases)
        clusters = np.repeat(np.arange(n_bases), rng.integers(1, 11, size=n_bases))
        e = stats.estimate((rng.random(len(clusters)) < p[clusters]).astype(float), clusters)
        covered += e.low <= rate <= e.high
    assert covered / STUDIES >= 0.94, covered / STUDIES


def test_the_t_quantile_matches_tables():
    assert stats.t_quantile(4) == pytest.approx(2.776, abs=0.001)
    assert [round(stats.t_quantile(d), 3) for d in (10, 29, 249)] == [2.228, 2.045, 1.970]


def test_only_done_trials_count_and_the_others_are_counted_by_status():
    df = table(
        [
            ("a", None, "done", True, 0.8, 1.0),
            ("a", "LB1", "not_applicable", None, None, 0.0),
            ("a", "SB1", "aborted", None, None, 0.5),
            ("b", None, "done", False, 0.0, 1.0),
            ("b", "LB1", "skipped", None, None, 0.0),
        ]
    )
    assert stats.status_counts(df) == {"done": 2, "not_applicable": 1, "aborted": 1, "skipped": 1}
    spl = stats.metric_estimate(df, "spl")
    assert spl.mean == pytest.approx(0.4) and spl.n_trials == 2


def test_paired_sensitivity_compares_each_perturbation_with_its_own_base():
    rows = []
    for k in range(20):
        base = 0.3 + 0.03 * k  # bases differ a lot; the perturbation costs each exactly 0.2
        rows += [(f"b{k}", None, "done", True, base, 1.0), (f"b{k}", "LB2", "done", True, base - 0.2, 0.0)]
    rows.append(("b20", "LB2", "done", True, 0.0, 0.0))  # its original was not done: left out
    sensitivity = stats.paired_sensitivity(table(rows), "spl", np.random.default_rng(0))
    assert list(sensitivity) == ["LB2"]
    lb2 = sensitivity["LB2"]
    assert lb2.mean == pytest.approx(-0.2) and lb2.n_clusters == 20
    assert lb2.high - lb2.low < 1e-9  # the pairing removes the spread between bases


def test_paired_difference_matches_trials_by_instance_id():
    a = table([("a", None, "done", True, 0.9, 1.0), ("b", None, "done", True, 0.7, 1.0)])
    b = table([("b", None, "done", True, 0.5, 1.0), ("a", None, "done", True, 0.6, 1.0)])
    b.loc[b["base_id"] == "a", "status"] = "aborted"
    diff = stats.paired_difference(a, b, "spl", np.random.default_rng(0))
    assert diff.mean == pytest.approx(0.2) and diff.n_trials == 1


def test_running_estimate_counts_the_trials_affordable_with_each_budget():
    df = table(
        [
            ("a", None, "done", True, 1.0, 2.0),
            ("a", "LB1", "done", False, 0.0, 0.0),
            ("b", None, "done", True, 0.5, 2.0),
        ]
    )
    at = stats.running_estimate(df, "spl", np.array([1.0, 2.0, 3.9, 4.0, 10.0]))
    assert at[0] != at[0]  # NaN: nothing affordable yet
    assert at[1:] == pytest.approx([0.5, 0.5, 0.5, 0.5])
    assert list(stats.trials_at_cost(df, np.array([1.0, 2.0, 4.0]))) == [0, 2, 3]
    assert stats.trials_per_unit_cost(df) == pytest.approx(3 / 4.0)


def test_error_vs_cost_bins_the_largest_cost_across_seeds_in_50_and_averages_over_seeds():
    seed_a = table([("a", None, "done", True, 1.0, 5.0), ("b", None, "done", True, 0.0, 5.0)])  # ends at cost 10
    seed_b = table([("a", None, "done", True, 0.4, 10.0), ("b", None, "done", True, 0.4, 10.0)])  # ends at 20
    curve = stats.error_vs_cost([(seed_a, 0.5), (seed_b, 0.5)], "spl")
    assert len(curve.costs) == 50 and curve.costs[-1] == pytest.approx(20.0)
    # At a budget of 10: seed a has its final estimate 0.5 (error 0), seed b has 0.4 (error 0.1).
    k = int(np.argmin(np.abs(curve.costs - 10.0)))
    assert curve.mean[k] == pytest.approx(0.05) and curve.std[k] == pytest.approx(np.std([0.0, 0.1], ddof=1))
    # Below a budget of 5 neither seed has run a trial; between 5 and 10 only seed a has.
    assert np.isnan(curve.mean[0]) and curve.mean[15] == pytest.approx(0.5) and np.isnan(curve.std[15])


def test_records_and_the_results_table_give_the_same_frame():
    scene = Scene({"cup": Pose(0.0, 0.0)})
    record = TrialRecord(
        index=0,
        base_id="c-0",
        perturbation=None,
        axis=None,
        family="place",
        staging="reset",
        repeat=0,
        status="done",
        instance=Instance("c-0", "place", "put the cup left", scene),
        cost=1.5,
        cumulative_cost=1.5,
        success=True,
        spl=0.75,
        progress=1.0,
    )
    df = stats.frame([record])
    assert df.loc[0, "instance_id"] == "c-0" and df.loc[0, "cumulative_cost"] == 1.5
    assert stats.metric_estimate(df, "spl").mean == 0.75
