import itertools

import numpy as np
import pytest

from lerobot_contrast import Evaluation, preview
from lerobot_contrast.contrast.cost import DistanceCost, ResetTimeCost
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.schedule import nearest_neighbour, path_cost, two_opt
from lerobot_contrast.contrast.strategy import make_plan
from lerobot_contrast.domains.language_table import LanguageTableTask

PERTURBATIONS = ["LB1", "LB2", "SB1", "SB2"]


@pytest.fixture(scope="module")
def language_table():
    task = LanguageTableTask()
    return task, task.sample(40, np.random.default_rng(11))


def plan(task, instances, strategy, order, seed=3):
    perturbations = task.perturbations.select(PERTURBATIONS) if strategy == "contrast" else []
    return make_plan(strategy, instances, perturbations, 1, np.random.default_rng(seed), order)


def planned_cost(task, trials, seed=3):
    records = preview(Evaluation(task, trials, DistanceCost(), seed=seed))
    return records[-1].cumulative_cost


def trial_keys(trials):
    return sorted((t.base.id, t.perturbation or "", t.staging, t.repeat) for t in trials)


@pytest.mark.parametrize("strategy", ["contrast", "standard"])
def test_cost_aware_order_stages_the_same_trials_for_much_less(language_table, strategy):
    task, instances = language_table
    iid, cheap = plan(task, instances, strategy, "iid"), plan(task, instances, strategy, "cost_aware")
    assert trial_keys(cheap) == trial_keys(iid)
    assert [t.index for t in cheap] == list(range(len(iid)))
    assert planned_cost(task, cheap) < 0.8 * planned_cost(task, iid)


def test_cost_aware_order_prices_staging_with_the_runs_cost_model(language_table):
    """Under reset time, handling each moved object (3 s) outweighs the distance, so the tour changes and is
    cheaper in seconds than the tour that minimises metres."""
    task, instances = language_table
    perturbations = task.perturbations.select(PERTURBATIONS)
    by_distance = make_plan("contrast", instances, perturbations, 1, np.random.default_rng(3), "cost_aware")
    seconds = ResetTimeCost()
    by_time = make_plan("contrast", instances, perturbations, 1, np.random.default_rng(3), "cost_aware", seconds)
    assert trial_keys(by_time) == trial_keys(by_distance) and by_time != by_distance

    def reset_seconds(trials):
        return preview(Evaluation(task, trials, seconds, seed=3))[-1].cumulative_cost

    assert reset_seconds(by_time) < reset_seconds(by_distance)


def test_each_base_keeps_its_chain_of_perturbations_behind_it(language_table):
    task, instances = language_table
    trials = plan(task, instances, "contrast", "cost_aware")
    chains = [list(group) for _, group in itertools.groupby(trials, key=lambda t: t.base.id)]
    assert len(chains) == len(instances)
    assert all([t.perturbation for t in chain] == [None, *PERTURBATIONS] for chain in chains)


def test_cost_aware_order_is_deterministic_for_a_seed(language_table):
    task, instances = language_table
    assert plan(task, instances, "contrast", "cost_aware") == plan(task, instances, "contrast", "cost_aware")


def test_unknown_order_names_the_flag_and_the_choices(language_table):
    task, instances = language_table
    with pytest.raises(UserError, match="--order: unknown order 'greedy'; choose from: iid, cost_aware"):
        plan(task, instances[:2], "contrast", "greedy")


def test_nearest_neighbour_and_2opt_find_the_straight_path_through_points_on_a_line():
    xs = np.random.default_rng(0).permutation(np.linspace(0.0, 1.0, 30))
    m = np.abs(xs[:, None] - xs[None, :])
    tour = two_opt(m, nearest_neighbour(m, start=0))
    assert sorted(tour) == list(range(30))
    assert path_cost(m, tour) == pytest.approx(1.0)


def test_2opt_leaves_no_improving_reversal_under_asymmetric_costs():
    rng = np.random.default_rng(5)
    m = rng.uniform(0.0, 1.0, size=(9, 9))
    start = rng.permutation(9)
    tour = two_opt(m, start)
    assert path_cost(m, tour) <= path_cost(m, start)
    for i, j in itertools.combinations(range(9), 2):
        flipped = tour.copy()
        flipped[i : j + 1] = flipped[i : j + 1][::-1]
        assert path_cost(m, flipped) >= path_cost(m, tour) - 1e-9
