"""The generic perturbations keep their claims on both shipped task files, and custom ones load by reference."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.domains import load_task
from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.domains.task_file.goals import involved
from tests.domains.task_file.task_file_fixtures import CUPS, write

EXAMPLES = ("so101_blocks", "lekiwi_fetch")


def changed(before: Scene, after: Scene) -> set[str]:
    """Objects moved, added or removed."""
    names = set(before.objects) | set(after.objects)
    return {n for n in names if before.objects.get(n) != after.objects.get(n)}


def goal_object(task, instance: Instance) -> str:
    predicate = instance.goal["predicate"]
    movable = [n for n in (predicate["subject"], predicate.get("near")) if n in task.spec.objects]
    return next(n for n in movable if task.spec.objects[n].movable)


def check_claim(task, axis: str, base: Instance, out: Instance) -> None:
    moved = changed(base.scene, out.scene)
    if axis == "L":  # new wording, same behaviour
        assert not moved and out.instruction != base.instruction
        assert out.goal["slots"] == base.goal["slots"] and out.goal["predicate"] == base.goal["predicate"]
    elif axis == "LB":  # new wording, different behaviour
        assert not moved and out.instruction != base.instruction
        assert out.goal["predicate"] != base.goal["predicate"]
    elif axis == "S":  # one object the instruction does not involve moves, appears or goes; the goal stays
        assert out.goal == base.goal and out.instruction == base.instruction and len(moved) == 1
        (name,) = moved
        assert name not in involved(base.goal, task.spec.objects)
        if name in out.scene.objects:
            pose = out.scene.objects[name]
            spacing = task.spec.workspace.min_spacing
            assert all(
                pose.distance_to(out.scene.objects[n]) >= spacing for n in involved(base.goal, task.spec.objects)
            )
    else:  # SB: the goal object moves, so the robot must do something else for the same words
        assert out.goal == base.goal and moved == {goal_object(task, base)}
        assert out.scene.objects[goal_object(task, base)].distance_to(base.scene.objects[goal_object(task, base)]) > 0


@pytest.mark.parametrize("example", EXAMPLES)
def test_every_generic_perturbation_keeps_its_claim_on_the_shipped_examples(example):
    task = load_task(example)
    rng = np.random.default_rng(3)
    applied, added_removed = Counter(), Counter()
    for base in task.sample(30, rng):
        for perturbation in task.perturbations:
            out = perturb(task, perturbation, base, rng)
            if out is None:
                continue
            applied[perturbation.name] += 1
            assert out.id == f"{base.id}/{perturbation.name}" and out.base_id == base.id
            assert not task.is_achieved(out, out.scene)
            check_claim(task, perturbation.axis, base, out)
            if perturbation.name == "S2":
                added_removed[len(out.scene.objects) > len(base.scene.objects)] += 1
    assert set(applied) == {p.name for p in task.perturbations}, applied
    assert added_removed[True] > 0 and added_removed[False] > 0


@pytest.fixture
def cups(tmp_path):
    return load_task_file(write(tmp_path, CUPS))


def hand_built(task) -> Instance:
    scene = Scene({"red_cup": Pose(0.5, 0.0), "blue_cup": Pose(0.5, 0.15)})
    return task.make_instance("cups-x", "move", {"cup": "red_cup", "side": "left"}, scene)


def test_flip_turns_the_region_word_and_the_goal_around(cups):
    base = hand_built(cups)
    out = perturb(cups, cups.perturbations.get("LB"), base, np.random.default_rng(0))
    assert base.instruction == "move the red cup to the left"
    assert out.instruction == "move the red cup to the right"
    assert out.goal["predicate"] == {"subject": "red_cup", "in": "right"}


def test_paraphrase_uses_the_synonyms_and_the_referents_other_words(tmp_path):
    task = load_task_file(
        write(
            tmp_path,
            CUPS.replace("{colour: red, category: cup,", "{colour: red, category: cup, words: [red cup, red mug],"),
        )
    )
    rng = np.random.default_rng(0)
    seen = {perturb(task, task.perturbations.get("L"), hand_built(task), rng).instruction for _ in range(40)}
    assert seen == {"push the red cup to the left", "move the red mug to the left", "push the red mug to the left"}


def test_move_goal_object_moves_the_subject_out_of_the_way_of_its_goal(cups):
    base = hand_built(cups)
    for seed in range(20):
        out = perturb(cups, cups.perturbations.get("SB"), base, np.random.default_rng(seed))
        red = out.scene.objects["red_cup"]
        assert red.distance_to(base.scene.objects["red_cup"]) >= 0.1 and not cups.spec.workspace.regions[
            "left"
        ].contains(red.x, red.y)
        assert red.distance_to(out.scene.objects["blue_cup"]) >= 0.1


def test_custom_perturbations_load_by_module_function_with_params_and_the_task(tmp_path):
    text = CUPS.replace(
        "  - {name: SB, kind: move_goal_object}\n",
        "  - {name: L2, axis: L, function: 'tests.domains.task_file.task_file_fixtures:louder', params: {suffix: ', please'}}\n"
        "  - {name: LB2, axis: LB, function: 'tests.domains.task_file.task_file_fixtures:other_cup'}\n",
    )
    task = load_task_file(write(tmp_path, text))
    base, rng = hand_built(task), np.random.default_rng(0)
    assert task.perturbations.get("L2").axis == "L" and task.perturbations.get("LB2").axis == "LB"
    assert perturb(task, task.perturbations.get("L2"), base, rng).instruction == "move the red cup to the left, please"
    other = perturb(task, task.perturbations.get("LB2"), base, rng)
    assert other.instruction == "move the blue cup to the left" and other.goal["predicate"]["subject"] == "blue_cup"


def test_a_custom_module_beside_the_task_file_is_found(tmp_path):
    (tmp_path / "my_perturbations.py").write_text(
        "def shout(instance, rng):\n    return instance.derive(instruction=instance.instruction.upper())\n"
    )
    text = CUPS.replace(
        "{name: SB, kind: move_goal_object}", "{name: SHOUT, axis: L, function: 'my_perturbations:shout'}"
    )
    task = load_task_file(write(tmp_path, text))
    out = perturb(task, task.perturbations.get("SHOUT"), hand_built(task), np.random.default_rng(0))
    assert out.instruction == "MOVE THE RED CUP TO THE LEFT" and out.perturbation == "SHOUT"
