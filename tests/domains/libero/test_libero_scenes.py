"""The four perturbations on real LIBERO scenes (libero_object task 0 in full, one task of each other suite, in
LeRobot's LiberoEnv): instructions change as declared, staged objects move by the planned distance after settling,
and LIBERO's own predicates judge the goal."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_contrast import load_task
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import perturb

pytestmark = pytest.mark.slow
SETTLED_M = 0.005


def _staged(robot, task, seed: int = 0):
    instance = task.sample(1, np.random.default_rng(seed))[0]
    robot.stage_scene(instance.scene)
    return instance.derive(scene=robot.read_scene())


def _displacements(before: Scene, after: Scene) -> dict[str, float]:
    return {name: before.objects[name].distance_to(pose) for name, pose in after.objects.items()}


def test_an_original_starts_from_its_libero_init_state_and_is_not_yet_achieved(libero_robot, object_task):
    instance = object_task.sample(1, np.random.default_rng(0))[0]
    libero_robot.stage_scene(instance.scene)
    after = libero_robot.read_scene()
    assert max(_displacements(instance.scene, after).values()) < SETTLED_M
    assert not object_task.is_achieved(instance, after)
    observation = libero_robot.get_observation()
    assert observation["image"].shape == observation["image2"].shape == (128, 128, 3)
    assert len([k for k in observation if k.startswith(("eef.", "gripper."))]) == 8


@pytest.mark.parametrize("name", ["S", "SB"])
def test_a_scene_perturbation_moves_objects_by_the_planned_distance_after_settling(libero_robot, object_task, name):
    current = _staged(libero_robot, object_task)
    perturbed = perturb(object_task, object_task.perturbations.get(name), current, np.random.default_rng(1))
    assert perturbed is not None and perturbed.instruction == current.instruction
    planned = _displacements(current.scene, perturbed.scene)
    moved = [n for n, d in planned.items() if d > 0]
    goal_objects = {"alphabet_soup_1", "basket_1"}
    assert len(moved) == 1 and (moved[0] in goal_objects) == (name == "SB")
    libero_robot.stage_scene(perturbed.scene)
    actual = _displacements(current.scene, libero_robot.read_scene())
    assert planned[moved[0]] >= 0.05
    assert all(abs(actual[n] - planned[n]) <= SETTLED_M for n in planned), (planned, actual)


def test_language_perturbations_change_the_instruction_as_declared(libero_robot, object_task):
    current = _staged(libero_robot, object_task)
    rng = np.random.default_rng(2)
    paraphrase = perturb(object_task, object_task.perturbations.get("L"), current, rng)
    assert paraphrase.instruction != current.instruction and paraphrase.goal == current.goal
    assert paraphrase.scene == current.scene
    other = perturb(object_task, object_task.perturbations.get("LB"), current, rng)
    ((_, new, place),) = other.goal["predicates"]
    assert new != "alphabet_soup_1" and place == "basket_1_contain_region"
    assert "alphabet soup" not in other.instruction and new.removesuffix("_1").replace("_", " ") in other.instruction


def test_the_goal_is_judged_by_libero_with_teleported_objects(libero_robot, object_task):
    current = _staged(libero_robot, object_task)
    other = perturb(object_task, object_task.perturbations.get("LB"), current, np.random.default_rng(3))
    ((_, new, _),) = other.goal["predicates"]
    basket = current.scene.objects["basket_1"]

    def teleported(name: str) -> Scene:
        pose = current.scene.objects[name]
        libero_robot.stage_scene(current.scene.with_object(name, Pose(basket.x, basket.y, pose.yaw)))
        return libero_robot.read_scene()

    in_basket = teleported("alphabet_soup_1")
    assert object_task.is_achieved(current, in_basket)
    assert not object_task.is_achieved(other, in_basket)  # after ΔLB the original object is the wrong one
    libero_robot.stage_scene(current.scene)
    assert object_task.is_achieved(other, teleported(new))


def _where_every_perturbation_applies(task):
    """The suite's first task whose first init state every perturbation applies to."""
    for task_id in task.task_ids:
        instance = task.instance(task_id, 0)
        if all(perturb(task, p, instance, np.random.default_rng(0)) for p in task.perturbations):
            return instance
    raise AssertionError(f"no task of {task.suite} takes every perturbation at its first init state")


# Each suite's scene is a new LiberoEnv (tens of seconds on a CPU): one task each, after libero_object's tests.
@pytest.mark.parametrize("suite", ["libero_spatial", "libero_goal", "libero_10"])
def test_every_perturbation_applies_on_a_real_scene_of_the_other_suites(libero_robot, suite):
    task = load_task(suite)
    instance = _where_every_perturbation_applies(task)
    libero_robot.stage_scene(instance.scene)
    current = instance.derive(scene=libero_robot.read_scene())  # some init states settle by more than 5 mm
    assert not task.is_achieved(current, current.scene)
    out = {p.name: perturb(task, p, current, np.random.default_rng(0)) for p in task.perturbations}
    assert out["L"].instruction != current.instruction and out["L"].goal == current.goal
    assert out["LB"].instruction != current.instruction and out["LB"].goal != current.goal
    assert not task.is_achieved(out["LB"], current.scene)  # the rewritten goal, judged by LIBERO's predicates
    for name in ("S", "SB"):
        planned = _displacements(current.scene, out[name].scene)
        libero_robot.stage_scene(out[name].scene)
        actual = _displacements(current.scene, libero_robot.read_scene())
        assert max(planned.values()) >= 0.05
        assert all(abs(actual[n] - planned[n]) <= SETTLED_M for n in planned), (name, planned, actual)
