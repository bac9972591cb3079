from dataclasses import replace

import numpy as np
import pytest

from lerobot_contrast.contrast.cost import DistanceCost
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.strategy import make_plan
from lerobot_contrast.contrast.trial import Outcome
from lerobot_contrast.spine.evaluation import BudgetError, Evaluation, assume_unchanged, check_budget
from lerobot_contrast.spine.evaluation import run as run_evaluation

from .toy_task import ToyTask


def bases(n, side="right"):
    return [
        Instance(
            f"toy-{k}", "push", f"push a {side}", Scene({"a": Pose(0.0, 0.0), "b": Pose(0.5, float(k))}), {"side": side}
        )
        for k in range(n)
    ]


def pusher(to: str | None = None):
    """Pushes `a` to the instructed side (or always to `to`), like a policy that solves or confuses the task."""

    def execute(context):
        instance = context.instance
        side = to or instance.goal["side"]
        after = instance.scene.with_object("a", Pose(0.15 if side == "right" else -0.15, 0.0))
        return Outcome(
            success=ToyTask().is_achieved(instance, after), steps=1, path_length=0.15, scene_after=after, duration_s=0.0
        )

    return execute


def run(task, strategy, instances, names=None, budget=None, execute=None, repeats=1, seed=0):
    perturbations = task.perturbations.select(names) if strategy == "contrast" else []
    plan = make_plan(strategy, instances, perturbations, repeats, np.random.default_rng(seed))
    return run_evaluation(Evaluation(task, plan, DistanceCost(), budget, seed, execute=execute or pusher())).records


def test_contrast_runs_each_base_then_its_perturbations_without_resetting():
    task = ToyTask()
    records = run(task, "contrast", bases(2), ["LB", "SB"])
    assert [(r.base_id, r.perturbation, r.staging) for r in records] == [
        ("toy-0", None, "reset"),
        ("toy-0", "LB", "in_place"),
        ("toy-0", "SB", "in_place"),
        ("toy-1", None, "reset"),
        ("toy-1", "LB", "in_place"),
        ("toy-1", "SB", "in_place"),
    ]
    costs = [r.cost for r in records]
    # storage -> base 0 moves a and b by 1 m each; the language perturbation is free; SB recentres a (0.15 m);
    # base 1 then restages a (0.15 m) and b (1 m).
    assert costs == pytest.approx([2.0, 0.0, 0.15, 1.15, 0.0, 0.15])
    assert [r.cumulative_cost for r in records] == pytest.approx(np.cumsum(costs))
    assert records[1].instance.instruction == "push a left" and records[1].instance.id == "toy-0/LB"


@pytest.mark.parametrize(("budget", "n_trials"), [(2.0, 3), (2.1, 3), (2.15, 4), (100.0, 6)])
def test_algorithm_1_runs_the_trial_that_crosses_the_budget_then_stops(budget, n_trials):
    records = run(ToyTask(), "contrast", bases(2), ["LB", "SB"], budget=budget)
    assert len(records) == n_trials
    assert all(r.cumulative_cost <= budget for r in records[:-1])


def test_a_perturbation_whose_goal_is_already_achieved_is_skipped_at_no_cost():
    # A confused policy always pushes left, so after the base the flipped instruction ("left") is already met.
    records = run(ToyTask(), "contrast", bases(1), ["LB"], execute=pusher(to="left"))
    assert [r.status for r in records] == ["done", "not_applicable"]
    assert records[1].cost == 0.0 and records[1].instance is None


def test_standard_restages_every_instance_in_a_seeded_iid_order():
    task = ToyTask()
    instances = bases(6)
    first = run(task, "standard", instances, seed=3)
    again = run(task, "standard", instances, seed=3)
    other = run(task, "standard", instances, seed=4)
    ids = [r.base_id for r in first]
    assert sorted(ids) == sorted(i.id for i in instances)
    assert ids == [r.base_id for r in again] and ids != [r.base_id for r in other]
    assert all(r.staging == "reset" and r.perturbation is None for r in first)


def test_limited_intervention_reuses_the_scene_and_resets_only_when_infeasible():
    task = ToyTask()
    instances = [bases(1, "right")[0], bases(1, "left")[0].derive(id="toy-1"), bases(1, "left")[0].derive(id="toy-2")]
    records = run(task, "limited_intervention", instances)
    # The first needs a reset from storage; "left" after "right" is feasible in place; "left" again is already met.
    assert [r.staging for r in records] == ["reset", "in_place", "reset"]
    assert records[1].cost == 0.0 and records[2].cost == pytest.approx(0.15)


def test_repeats_restage_the_same_instance():
    records = run(ToyTask(), "contrast", bases(1), ["SB"], repeats=2)
    assert [(r.perturbation, r.repeat) for r in records] == [(None, 0), (None, 1), ("SB", 0), ("SB", 1)]
    assert records[1].instance == records[0].instance and records[1].cost == pytest.approx(0.15)
    assert records[3].instance == records[2].instance


def test_same_seed_gives_the_same_plan_and_records():
    task = ToyTask()
    instances = task.sample(5, np.random.default_rng(7))
    assert instances == task.sample(5, np.random.default_rng(7))
    # When each trial started is the wall clock's, not the plan's: two runs a second apart differ there alone.
    first, again = ([replace(r, started_at=None) for r in run(task, "contrast", instances, seed=1)] for _ in range(2))
    assert first == again


def test_dry_run_assumes_the_scene_is_left_as_staged():
    records = run(ToyTask(), "contrast", bases(1), ["LB", "SB"], execute=assume_unchanged)
    assert [r.cost for r in records] == pytest.approx([2.0, 0.0, 0.0])


def test_budget_below_the_first_trial_is_refused_with_its_cost():
    task = ToyTask()
    plan = make_plan("contrast", bases(1), [], 1, np.random.default_rng(0))
    with pytest.raises(BudgetError, match=r"--budget 1 m is below the cost of staging the first trial \(2.00 m\)"):
        check_budget(Evaluation(task, plan, DistanceCost(), budget=1.0))
    check_budget(Evaluation(task, plan, DistanceCost(), budget=2.0))


def test_unknown_strategy_and_perturbation_name_the_flag_and_the_choices():
    task = ToyTask()
    with pytest.raises(UserError, match="--strategy: unknown strategy 'iid'; choose from: standard, contrast"):
        make_plan("iid", bases(1), [], 1, np.random.default_rng(0))
    with pytest.raises(
        UserError, match="--perturbations: unknown perturbation 'LB9' for task 'toy'; choose from: LB, SB, S"
    ):
        task.perturbations.select(["LB9"])
