"""The VLN task: the shipped example set, grounding, judging subgoal progress, reference routes and nDTW."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_contrast import Evaluation, preview
from lerobot_contrast.contrast import DistanceCost, make_plan
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains import load_task
from lerobot_contrast.domains.vln import VLNTask
from lerobot_contrast.domains.vln.apartment import resample
from lerobot_contrast.domains.vln.wording import name_of


@pytest.fixture(scope="module")
def task() -> VLNTask:
    return load_task("vln_paper")


def test_the_shipped_set_is_five_arrangements_with_two_subgoal_instructions(task):
    assert [i.id for i in task.examples] == ["vln-1", "vln-2", "vln-3", "vln-4", "vln-5"]
    assert len({tuple(sorted(i.scene.objects.items())) for i in task.examples}) == 5
    for instance in task.examples:
        assert task.rebase(instance, instance.scene) == instance
        assert not task.is_achieved(instance, instance.scene)
        first, final = instance.goal["subgoals"]
        assert instance.instruction.index(name_of(first)) < instance.instruction.index(name_of(final))
        assert task.reference_length(instance) > 3.0
    assert task.outcome == "subgoals" and task.subgoals(task.examples[3]) == ["the TV stand", "the desk"]


def test_sampling_draws_the_shipped_instances_and_refuses_more(task):
    drawn = task.sample(5, np.random.default_rng(3))
    assert sorted(i.id for i in drawn) == [f"vln-{k}" for k in range(1, 6)]
    assert drawn == task.sample(5, np.random.default_rng(3))
    with pytest.raises(UserError, match="--n_instances"):
        task.sample(6, np.random.default_rng(0))
    with pytest.raises(UserError, match="--families"):
        VLNTask(families=["pick_place"])


def test_the_paper_shaped_plan_is_75_trials_and_perturbations_cost_little(task):
    rng = np.random.default_rng(0)
    plan = make_plan("contrast", task.sample(5, rng), list(task.perturbations), repeats=3, rng=rng)
    records = preview(Evaluation(task, plan, DistanceCost()))
    assert len(plan) == 75 and [r.status for r in records] == ["done"] * 75
    cost = {axis: sum(r.cost for r in records if r.axis == axis) for axis in (None, "L", "LB", "S", "SB")}
    assert cost["L"] == cost["LB"] == 0.0 and 0 < cost["S"] + cost["SB"] < 0.2 * cost[None]


def path_through(*points: tuple[float, float]) -> list[Pose]:
    return [Pose(x, y) for x, y in points]


def test_progress_counts_subgoals_reached_in_order_the_last_where_the_robot_stopped(task):
    instance = task.examples[0]  # lamp at (4.1, 3.5), then the bookshelf along the wall at x = 0.25, y = 1.8
    start, near_lamp, at_shelf = (7.0, 1.0), (4.1, 2.9), (0.9, 1.8)
    scene = instance.scene
    assert task.judge(instance, path_through(start, near_lamp, at_shelf), scene.with_robot(None)).progress == 1.0
    assert task.judge(instance, path_through(start, near_lamp, at_shelf), scene.with_robot(None)).success
    assert task.judge(instance, path_through(start, near_lamp), scene.with_robot(None)).progress == 0.5
    assert task.judge(instance, path_through(start, at_shelf), scene.with_robot(None)).progress == 0.0
    passed_shelf = task.judge(instance, path_through(start, near_lamp, at_shelf, (4.0, 1.0)), scene.with_robot(None))
    assert passed_shelf.progress == 0.5 and not passed_shelf.success  # it did not stop there
    # The robot's final pose in the scene counts as where it stopped.
    assert task.judge(instance, path_through(start, near_lamp), scene.with_robot(Pose(*at_shelf))).success


def test_the_reference_route_is_the_best_path_and_ndtw_scores_paths_against_it(task):
    instance = task.examples[1]
    route = task.reference_route(instance)
    follows = [Pose(x, y) for x, y in resample(route.points, 0.25)]  # positions a step apart, as a robot's
    assert task.judge(instance, follows, instance.scene.with_robot(None)).success
    assert task.reference_length(instance) == pytest.approx(route.length)
    assert task.ndtw(instance, follows) == pytest.approx(1.0, abs=0.05)
    shifted = [Pose(p.x, p.y + 0.3) for p in follows]
    assert 0.3 < task.ndtw(instance, shifted) < 0.9
    assert task.ndtw(instance, []) is None
