"""i.i.d. sampling: determinism, ids, valid non-overlapping scenes, feasible unsolved goals, conditions."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.domains.language_table import (
    FAMILIES,
    LanguageTableTask,
    board,
    enumerate_conditions,
    geometry,
    push_target,
)
from lerobot_contrast.domains.language_table.wording import render


@pytest.fixture(scope="module")
def instances() -> list[Instance]:
    return LanguageTableTask().sample(300, np.random.default_rng(0))


def test_same_seed_gives_identical_instances(instances):
    again = LanguageTableTask().sample(300, np.random.default_rng(0))
    assert [i.to_json() for i in again] == [i.to_json() for i in instances]
    other = LanguageTableTask().sample(10, np.random.default_rng(1))
    assert [i.instruction for i in other] != [i.instruction for i in instances[:10]]


def test_ids_and_json_round_trip(instances):
    assert [i.id for i in instances[:3]] == ["lt-0000", "lt-0001", "lt-0002"]
    assert all(i.base_id == i.id and i.perturbation is None for i in instances)
    for inst in instances:
        assert Instance.from_json(json.loads(json.dumps(inst.to_json()))) == inst


def test_families_are_uniform(instances):
    counts = Counter(i.family for i in instances)
    assert set(counts) == set(FAMILIES)
    assert all(40 <= c <= 80 for c in counts.values()), counts


def test_scenes_are_valid_resets(instances):
    for inst in instances:
        scene = inst.scene
        assert list(scene.objects) == list(board.BLOCK_MODES["BLOCK_8"])
        assert geometry.inside_target_bounds((scene.robot.x, scene.robot.y))
        for pose in scene.objects.values():
            assert geometry.inside_target_bounds((pose.x, pose.y))
            assert pose.distance_to(scene.robot) > board.ARM_DISTANCE_THRESHOLD
            assert 0.0 <= pose.yaw < 2 * np.pi
        for (a, pa), (b, pb) in itertools.combinations(scene.objects.items(), 2):
            assert not geometry.footprints_overlap(a, pa, b, pb)


def test_goals_are_grounded_unsolved_and_worded(instances):
    task = LanguageTableTask()
    for inst in instances:
        assert task.rebase(inst, inst.scene) == inst
        assert not task.is_achieved(inst, inst.scene)
        assert inst.instruction == render(inst.family, inst.goal["words"])
        block, target = push_target(inst, inst.scene)
        assert block == inst.goal["block"] and target.shape == (2,)
        if inst.family != "block2absolutelocation":  # absolute locations lie on the board's edges
            assert geometry.inside_target_bounds(target)


def test_family_filter_and_bad_input():
    task = LanguageTableTask(families=["separate"])
    assert {i.family for i in task.sample(20, np.random.default_rng(2))} == {"separate"}
    with pytest.raises(ValueError, match="choose from"):
        LanguageTableTask(families=["block2moon"])
    with pytest.raises(ValueError, match="unknown block mode"):
        LanguageTableTask(block_mode="BLOCK_9")


def test_block4_uses_short_referring_expressions():
    texts = " | ".join(i.instruction for i in LanguageTableTask("BLOCK_4").sample(60, np.random.default_rng(3)))
    assert " block" in texts  # "<color> block" is possible when colours are unique


def test_task_protocol_attributes():
    task = LanguageTableTask()
    assert task.name == "language_table"
    assert isinstance(task.perturbations, PerturbationRegistry)
    assert [p.name for p in task.perturbations] == ["L", "LB1", "LB2", "S", "SB1", "SB2"]
    assert [p.axis for p in task.perturbations] == ["L", "LB", "LB", "S", "SB", "SB"]
    assert task.blocks == board.BLOCK_MODES["BLOCK_8"]


def test_enumerate_conditions_matches_benchmark():
    conditions = enumerate_conditions("BLOCK_8")
    assert len(conditions) == 696 == len(set(conditions))
    assert Counter(c[0] for c in conditions) == {
        "block2block": 56,
        "block2absolutelocation": 72,
        "block2relativelocation": 64,
        "block2blockrelativelocation": 448,
        "separate": 56,
    }
    assert LanguageTableTask("BLOCK_4").enumerate_conditions() == enumerate_conditions("BLOCK_4")
    assert len(enumerate_conditions("BLOCK_4")) == 12 + 36 + 32 + 96 + 12


def test_footprint_overlap_is_oriented():
    a = board.SHAPE_FOOTPRINT["cube"][0]
    from lerobot_contrast.contrast.scene import Pose

    assert geometry.footprints_overlap("blue_cube", Pose(0.3, 0.0), "green_cube", Pose(0.3, a))
    assert not geometry.footprints_overlap("blue_cube", Pose(0.3, 0.0), "green_cube", Pose(0.3, a + 0.003))
    # A cube turned 45 degrees reaches further along y, so the same gap now overlaps.
    assert geometry.footprints_overlap("blue_cube", Pose(0.3, 0.0), "green_cube", Pose(0.3, a + 0.003, np.pi / 4))
    # The moon is long along its local x and thin along local y.
    assert not geometry.footprints_overlap("red_moon", Pose(0.3, 0.0), "blue_moon", Pose(0.3, 0.03))
    assert geometry.footprints_overlap("red_moon", Pose(0.3, 0.0), "blue_moon", Pose(0.3, 0.03, np.pi / 2))


def test_scene_sampler_is_fast_and_dense_enough_for_clumps():
    rng = np.random.default_rng(4)
    scenes = [geometry.sample_scene(board.BLOCK_MODES["BLOCK_8"], rng) for _ in range(300)]
    gaps = [pa.distance_to(pb) for s in scenes for (_, pa), (_, pb) in itertools.combinations(s.objects.items(), 2)]
    # Footprints, not circumscribed circles, bound the packing: neighbours can sit closer than 0.056 m.
    assert min(gaps) < 0.05
    assert sum(g < board.SEPARATE_JOINED_DISTANCE for g in gaps) > 100


def test_instruction_to_array():
    from lerobot_contrast.domains.language_table import instruction_to_array

    arr = instruction_to_array("push the red moon")
    assert arr.shape == (512,) and arr.dtype == np.int32
    assert bytes(arr[:17].astype(np.uint8)) == b"push the red moon" and not arr[17:].any()
    assert instruction_to_array("é")[:2].tolist() == [0xC3, 0xA9]
    with pytest.raises(ValueError, match="512"):
        instruction_to_array("x" * 513)


def test_no_heavy_imports():
    code = (
        "import sys, lerobot_contrast.domains.language_table\n"
        "bad = [m for m in ('gymnasium', 'pymunk', 'torch', 'lerobot') if m in sys.modules]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_storage_scene_holds_every_block_off_the_workspace():
    task = LanguageTableTask()
    storage = task.storage_scene()
    assert list(storage.objects) == list(task.blocks)
    for pose in storage.objects.values():
        assert pose.y > board.Y_MAX  # beside the board, so staging the first trial moves every block
    for (a, pa), (b, pb) in itertools.combinations(storage.objects.items(), 2):
        assert not geometry.footprints_overlap(a, pa, b, pb)
