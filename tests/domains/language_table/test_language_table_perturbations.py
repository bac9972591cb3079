"""The six perturbations: applicability per family, what they change, wording, validity, determinism."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.domains.language_table import LanguageTableTask, board, geometry
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.perturbations import KEEP_CLEAR, MIN_MOVE
from lerobot_contrast.domains.language_table.wording import render

from .lt_helpers import ABS_WORDS, B2B_WORDS, B2BREL_WORDS, REL_WORDS, SEP_WORDS, make, scene

TASK = LanguageTableTask()
P = {p.name: p for p in TASK.perturbations}
APPLIES = {  # (perturbation, family) pairs that can ever apply
    "LB1": {fam.BLOCK2BLOCK, fam.B2B_RELATIVE, fam.SEPARATE},
    "LB2": {fam.ABSOLUTE, fam.RELATIVE, fam.B2B_RELATIVE},
    "SB1": {fam.BLOCK2BLOCK, fam.B2B_RELATIVE},
}


@pytest.fixture(scope="module")
def instances():
    return TASK.sample(100, np.random.default_rng(7))


def _left_behind(inst, fraction):
    """The instance in the scene a robot leaves after pushing its block `fraction` of the way to the target."""
    block, target = TASK.push_target(inst, inst.scene)
    old = inst.scene.objects[block]
    x, y = (1 - fraction) * np.array((old.x, old.y)) + fraction * target
    scene = inst.scene.with_object(block, Pose(float(x), float(y), old.yaw)).with_robot(Pose(old.x, old.y))
    return inst.derive(scene=scene)


@pytest.fixture(scope="module")
def results(instances):
    """Perturbations of each instance in its start scene, and in scenes left after a partial or full push."""
    rng = np.random.default_rng(8)
    bases = [*instances, *(_left_behind(i, 0.5) for i in instances), *(_left_behind(i, 1.0) for i in instances)]
    return [(inst, name, perturb(TASK, P[name], inst, rng)) for inst in bases for name in P]


def _changed(a, b) -> list[str]:
    return [n for n in a.objects if a.objects[n] != b.objects[n]]


def test_applicability_per_family(results):
    applied = {(inst.family, name) for inst, name, out in results if out is not None}
    for name, fams in APPLIES.items():
        assert {f for f, n in applied if n == name} <= fams, name
    for family in fam.FAMILIES:  # everything else applies somewhere in 100 instances
        for name in P:
            if family in APPLIES.get(name, fam.FAMILIES):
                assert (family, name) in applied, (family, name)


def test_results_are_valid_tests(results):
    for inst, name, out in results:
        if out is None:
            continue
        assert out.id == f"{inst.id}/{name}" and out.base_id == inst.id and out.perturbation == name
        assert out.family == inst.family
        assert out.instruction == render(out.family, out.goal["words"])
        assert not TASK.is_achieved(out, out.scene)
        assert TASK.rebase(out, out.scene) == out


def test_language_perturbations_keep_the_scene(results):
    for inst, name, out in results:
        if out is not None and name in ("L", "LB1", "LB2"):
            assert out.scene == inst.scene
            assert out.instruction != inst.instruction


def test_scene_perturbations_move_one_block_to_a_valid_place(results):
    for inst, name, out in results:
        if out is None or name not in ("S", "SB1", "SB2"):
            continue
        assert out.instruction == inst.instruction and out.scene.robot == inst.scene.robot
        (moved,) = _changed(inst.scene, out.scene)
        pose = out.scene.objects[moved]
        assert geometry.placement_ok(out.scene, moved, pose)
        assert pose.yaw == inst.scene.objects[moved].yaw
        involved = fam.involved_blocks(inst.goal)
        if name == "SB1":
            assert moved == inst.goal["target_block"]
        elif name == "SB2":
            assert moved == inst.goal["block"]
        else:
            assert moved not in involved
            # Same goal as the instance re-grounded where it stands (a relative target follows its block).
            assert out.goal == TASK.rebase(inst, inst.scene).goal
        if not (name == "SB2" and inst.family == fam.SEPARATE):
            assert pose.distance_to(inst.scene.objects[moved]) >= MIN_MOVE


def test_distractor_keeps_clear_of_the_task(results):
    for inst, name, out in results:
        if out is None or name != "S":
            continue
        (moved,) = _changed(inst.scene, out.scene)
        p = geometry.xy(out.scene, moved)
        for other in fam.involved_blocks(inst.goal):
            assert np.linalg.norm(p - geometry.xy(out.scene, other)) >= KEEP_CLEAR


def test_paraphrase_keeps_the_goal(results):
    for inst, name, out in results:
        if out is not None and name == "L":
            strip = lambda g: {k: v for k, v in g.items() if k != "words"}  # noqa: E731
            assert strip(out.goal) == strip(TASK.rebase(inst, inst.scene).goal)


def test_perturbations_are_deterministic(instances):
    for name, inst in itertools.product(P, instances[:20]):
        a = P[name].apply(inst, np.random.default_rng(3))
        b = P[name].apply(inst, np.random.default_rng(3))
        assert a == b


def test_lb1_swaps_referring_expressions_and_is_an_involution():
    start = scene(red_moon=(0.3, -0.1), blue_cube=(0.3, 0.1))
    inst = make(fam.BLOCK2BLOCK, {"block": "red_moon", "target_block": "blue_cube"}, B2B_WORDS, start)
    once = P["LB1"].apply(inst, np.random.default_rng(0))
    assert once.instruction == "push the blue cube close to the red moon"
    assert (once.goal["block"], once.goal["target_block"]) == ("blue_cube", "red_moon")
    twice = P["LB1"].apply(once, np.random.default_rng(0))
    assert twice.instruction == inst.instruction and twice.goal == inst.goal
    sep_start = scene(red_moon=(0.4, 0.05), blue_cube=(0.4, 0.0))
    sep = make(fam.SEPARATE, {"block": "red_moon", "avoid": ["blue_cube"], "avoid_mode": "named"}, SEP_WORDS, sep_start)
    swapped = P["LB1"].apply(sep, np.random.default_rng(0))
    assert swapped.instruction == "separate the blue cube from the red moon"
    assert swapped.goal["avoid"] == ["red_moon"]
    b2brel = make(
        fam.B2B_RELATIVE,
        {"block": "red_moon", "target_block": "blue_cube", "direction": "up"},
        B2BREL_WORDS,
        scene(red_moon=(0.35, -0.15), blue_cube=(0.4, 0.1)),
    )
    assert P["LB1"].apply(b2brel, np.random.default_rng(0)).instruction == "slide the blue cube above the red moon"


def test_lb1_does_not_apply_to_groups_or_single_block_families():
    clump = scene(red_moon=(0.4, 0.0), blue_cube=(0.4, 0.05), green_star=(0.4, -0.05), yellow_star=(0.35, 0.0))
    group = make(
        fam.SEPARATE, {"block": "red_moon", "avoid": [], "avoid_mode": "group"}, {**SEP_WORDS, "avoid": "clump"}, clump
    )
    assert P["LB1"].apply(group, np.random.default_rng(0)) is None
    start = scene(red_moon=(0.45, 0.15), blue_cube=(0.3, -0.1))
    absolute = make(fam.ABSOLUTE, {"block": "red_moon", "location": "top_left"}, ABS_WORDS, start)
    assert P["LB1"].apply(absolute, np.random.default_rng(0)) is None


@pytest.mark.parametrize(
    ("location", "word", "flipped_location", "flipped_word"),
    [
        ("top_left", "upper left corner", "bottom_right", "lower right corner"),
        ("top_right", "top right of the board", "bottom_left", "bottom left of the board"),
        ("center_left", "left side", "center_right", "right side"),
        ("bottom", "bottom side", "top", "top side"),
    ],
)
def test_lb2_flips_locations_to_the_matching_synonym(location, word, flipped_location, flipped_word):
    start = scene(red_moon=(0.375, 0.0), blue_cube=(0.3, -0.15))
    inst = make(fam.ABSOLUTE, {"block": "red_moon", "location": location}, {**ABS_WORDS, "location": word}, start)
    out = P["LB2"].apply(inst, np.random.default_rng(0))
    assert out.goal["location"] == flipped_location
    assert out.instruction == f"move the red moon to the {flipped_word}"


def test_lb2_unmatched_synonym_and_center():
    start = scene(red_moon=(0.375, 0.0), blue_cube=(0.3, -0.15))
    top = make(
        fam.ABSOLUTE, {"block": "red_moon", "location": "top"}, {**ABS_WORDS, "location": "towards your base"}, start
    )
    out = P["LB2"].apply(top, np.random.default_rng(0))
    assert out.goal["location"] == "bottom" and out.goal["words"]["location"] in ("bottom side", "bottom")
    center = make(
        fam.ABSOLUTE,
        {"block": "red_moon", "location": "center"},
        {**ABS_WORDS, "location": "middle"},
        scene(red_moon=(0.25, 0.2)),
    )
    assert P["LB2"].apply(center, np.random.default_rng(0)) is None


def test_lb2_flips_relative_directions():
    start = scene(red_moon=(0.375, 0.0), blue_cube=(0.3, -0.2))
    goal = {"block": "red_moon", "direction": "diagonal_up_left", "magnitude": "near"}
    words = {**REL_WORDS, "vertical": "upwards", "mode": "suffix", "slightly": "a bit"}
    inst = make(fam.RELATIVE, goal, words, start)
    assert inst.instruction == "push the red moon upwards and to the left a bit"
    out = P["LB2"].apply(inst, np.random.default_rng(0))
    assert out.instruction == "push the red moon downwards and to the right a bit"
    assert out.goal["direction"] == "diagonal_down_right"
    step = 0.15 / np.sqrt(2)
    assert out.goal["target_xy"] == pytest.approx([0.375 + step, step])
    b2brel = make(
        fam.B2B_RELATIVE,
        {"block": "red_moon", "target_block": "blue_cube", "direction": "left"},
        {**B2BREL_WORDS, "direction": "to the left side of the"},
        scene(red_moon=(0.3, 0.15), blue_cube=(0.4, 0.0)),
    )
    assert P["LB2"].apply(b2brel, np.random.default_rng(0)).instruction == (
        "slide the red moon to the right side of the blue cube"
    )


def test_lb2_rejects_flips_off_the_board():
    start = scene(red_moon=(0.26, 0.0), blue_cube=(0.45, -0.2))
    words = {**REL_WORDS, "diagonal": None, "horizontal": None, "vertical": "down"}
    inst = make(fam.RELATIVE, {"block": "red_moon", "direction": "down", "magnitude": "far"}, words, start)
    assert P["LB2"].apply(inst, np.random.default_rng(0)) is None  # 0.26 - 0.25 is off the board


def test_separate_source_move_stays_in_the_clump():
    start = scene(red_moon=(0.4, 0.05), blue_cube=(0.4, 0.0), robot=(0.25, -0.2))
    start = start.with_object("green_star", Pose(0.3, 0.2, 0.0))
    inst = make(fam.SEPARATE, {"block": "red_moon", "avoid": ["blue_cube"], "avoid_mode": "named"}, SEP_WORDS, start)
    out = P["SB2"].apply(inst, np.random.default_rng(0))
    assert out is not None
    assert out.scene.objects["red_moon"].distance_to(out.scene.objects["blue_cube"]) < board.SEPARATE_JOINED_DISTANCE
    old = fam.push_target(inst, inst.scene)[1]
    assert np.linalg.norm(fam.push_target(out, out.scene)[1] - old) >= MIN_MOVE


def test_perturbing_the_scene_left_behind():
    """After a success, language swaps of b2b are achieved (rejected) while moving the target applies."""
    start = scene(red_moon=(0.3, -0.1), blue_cube=(0.3, 0.1))
    inst = make(fam.BLOCK2BLOCK, {"block": "red_moon", "target_block": "blue_cube"}, B2B_WORDS, start)
    after = inst.derive(scene=start.with_object("red_moon", Pose(0.3, 0.06, 0.0)))
    rng = np.random.default_rng(0)
    assert perturb(TASK, P["LB1"], after, rng) is None
    assert perturb(TASK, P["L"], after, rng) is None
    moved = perturb(TASK, P["SB1"], after, rng)
    assert moved is not None and _changed(after.scene, moved.scene) == ["blue_cube"]


def test_a_location_that_is_already_a_direction_reads_as_english():
    start = scene(red_moon=(0.375, 0.0), blue_cube=(0.3, -0.15))
    top = make(
        fam.ABSOLUTE, {"block": "red_moon", "location": "top"}, {**ABS_WORDS, "location": "towards your base"}, start
    )
    assert top.instruction == "move the red moon towards your base"
    flipped = [P["LB2"].apply(top, np.random.default_rng(seed)).instruction for seed in range(6)]
    assert all(" to the " in text and "towards" not in text for text in flipped)
