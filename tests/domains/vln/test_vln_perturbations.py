"""The VLN perturbations keep their claims, checked against the grid planner on every shipped instance."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_contrast.contrast import DistanceCost
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.domains.vln import VLNTask, routes
from lerobot_contrast.domains.vln.apartment import hausdorff, resample
from lerobot_contrast.domains.vln.perturbations import PLACEMENT_GAP_M, _placement_ok
from lerobot_contrast.domains.vln.wording import synonyms

TASK = VLNTask()
CASES = [(instance, seed) for instance in TASK.examples for seed in (0, 1)]


def apply(name: str, instance, seed: int):
    out = perturb(TASK, TASK.perturbations.get(name), instance, np.random.default_rng(seed))
    assert out is not None, f"Δ{name} found nothing for {instance.id}"
    assert out.id == f"{instance.id}/{name}" and out.base_id == instance.id and out.perturbation == name
    return out


def moved(before, after) -> list[str]:
    return [n for n in before.scene.objects if before.scene.objects[n] != after.scene.objects[n]]


@pytest.mark.parametrize(("instance", "seed"), CASES)
def test_reword_changes_the_words_not_the_goal(instance, seed):
    out = apply("L", instance, seed)
    assert out.instruction != instance.instruction and out.scene == instance.scene
    assert out.goal["subgoals"] == instance.goal["subgoals"]
    for slot, name in zip(("first", "final"), out.goal["subgoals"], strict=True):
        assert out.goal["words"][slot] in synonyms(name) and out.goal["words"][slot] in out.instruction


@pytest.mark.parametrize(("instance", "seed"), CASES)
def test_a_new_final_goal_keeps_the_first_subgoal_and_changes_the_route(instance, seed):
    out = apply("LB", instance, seed)
    assert out.scene == instance.scene and out.goal["template"] == instance.goal["template"]
    assert out.goal["subgoals"][0] == instance.goal["subgoals"][0] != out.goal["subgoals"][1]
    assert out.goal["subgoals"][1] != instance.goal["subgoals"][1]
    assert routes.different_route(TASK.reference_route(instance), TASK.reference_route(out))


@pytest.mark.parametrize(("instance", "seed"), CASES)
def test_moving_a_passive_object_keeps_the_route_and_costs_under_a_metre(instance, seed):
    out = apply("S", instance, seed)
    [name] = moved(instance, out)
    assert name not in instance.goal["subgoals"] and out.instruction == instance.instruction
    assert routes.same_route(TASK.reference_route(instance), TASK.reference_route(out))
    assert 0.3 <= DistanceCost()(instance.scene, out.scene) <= 1.0
    assert _placement_ok(out.scene, name)


@pytest.mark.parametrize(("instance", "seed"), CASES)
def test_moving_a_goal_or_blocking_the_way_changes_the_route(instance, seed):
    out = apply("SB", instance, seed)
    [name] = moved(instance, out)
    before, after = TASK.reference_route(instance), TASK.reference_route(out)
    assert hausdorff(before.points, after.points) >= routes.DIFFERENT_ROUTE_M
    if name not in instance.goal["subgoals"]:  # it was put in the way: onto the old route
        assert routes.distance_to_object(out.scene, name, resample(before.points, 0.05)).min() < 0
    assert routes.start_is_free(out.scene, Pose.from_json(out.goal["start"])) and _placement_ok(out.scene, name)


def test_placement_keeps_furniture_apart_and_inside_the_room():
    scene = TASK.examples[0].scene
    couch = scene.objects["couch"]
    assert not _placement_ok(
        scene.with_object("lamp", Pose(couch.x, couch.y + 0.425 + 0.175 + PLACEMENT_GAP_M / 2)), "lamp"
    )
    assert _placement_ok(
        scene.with_object("lamp", Pose(couch.x, couch.y + 0.425 + 0.175 + 2 * PLACEMENT_GAP_M)), "lamp"
    )
    assert not _placement_ok(scene.with_object("lamp", Pose(0.1, 3.0)), "lamp")


def test_perturbations_do_not_apply_where_their_claim_cannot_hold():
    instance = TASK.examples[0]
    goals = {n: p for n, p in instance.scene.objects.items() if n in instance.goal["subgoals"]}
    only_goals = instance.derive(scene=Scene(goals, instance.scene.robot))  # nothing passive to move
    assert perturb(TASK, TASK.perturbations.get("S"), only_goals, np.random.default_rng(0)) is None
