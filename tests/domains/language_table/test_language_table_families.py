"""Success predicates at/inside/outside the benchmark thresholds, push targets, and rebasing."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.language_table import board, is_achieved, push_target, rebase
from lerobot_contrast.domains.language_table import families as fam

from .lt_helpers import ABS_WORDS, B2B_WORDS, B2BREL_WORDS, REL_WORDS, SEP_WORDS, make, scene


def _moved(instance, name, x, y):
    return instance.scene.with_object(name, Pose(x, y, 0.0))


@pytest.mark.parametrize(("dy", "expected"), [(0.049, True), (0.05, False), (0.051, False)])
def test_block2block_threshold(dy, expected):
    start = scene(red_moon=(0.3, -0.1), blue_cube=(0.3, 0.0))
    inst = make(fam.BLOCK2BLOCK, {"block": "red_moon", "target_block": "blue_cube"}, B2B_WORDS, start)
    assert not is_achieved(inst, start)
    assert is_achieved(inst, _moved(inst, "red_moon", 0.3, -dy)) is expected


@pytest.mark.parametrize(
    ("location", "distance", "expected"),
    [
        ("top_left", 0.114, True),
        ("top_left", 0.116, False),
        ("bottom", 0.114, True),
        ("center", 0.099, True),
        ("center", 0.101, False),
        ("center", 0.11, False),  # the centre uses the tighter 0.10
    ],
)
def test_absolute_location_threshold(location, distance, expected):
    lx, ly = board.LOCATIONS[location]
    start = scene(red_moon=(0.3, 0.15), blue_cube=(0.45, 0.1))
    words = {**ABS_WORDS, "location": "center"}
    inst = make(fam.ABSOLUTE, {"block": "red_moon", "location": location}, words, start)
    # Approach along x towards the board centre, so the test point stays on the table.
    sign = 1.0 if lx < board.CENTER_X else -1.0
    assert is_achieved(inst, _moved(inst, "red_moon", lx + sign * distance, ly)) is expected


def test_absolute_location_table_is_shifted_by_x_buffer():
    assert board.LOCATIONS["top_left"] == pytest.approx((0.125, -0.3048))
    assert board.LOCATIONS["center"] == pytest.approx((0.35, 0.0))
    assert board.LOCATIONS["bottom_right"] == pytest.approx((0.575, 0.3048))


@pytest.mark.parametrize(("dist", "expected"), [(0.099, True), (0.101, False)])
def test_relative_location_threshold(dist, expected):
    start = scene(red_moon=(0.45, 0.15), blue_cube=(0.3, -0.1))
    goal = {"block": "red_moon", "direction": "diagonal_up_left", "magnitude": "far"}
    inst = make(fam.RELATIVE, goal, REL_WORDS, start)
    tx, ty = inst.goal["target_xy"]
    step = 0.25 / np.sqrt(2)
    assert (tx, ty) == pytest.approx((0.45 - step, 0.15 - step))
    assert is_achieved(inst, _moved(inst, "red_moon", tx, ty + dist)) is expected


def test_relative_location_target_is_fixed_at_episode_start():
    start = scene(red_moon=(0.45, 0.0), blue_cube=(0.3, -0.15))
    inst = make(fam.RELATIVE, {"block": "red_moon", "direction": "up", "magnitude": "near"}, REL_WORDS, start)
    assert inst.goal["target_xy"] == pytest.approx([0.30, 0.0])
    now = _moved(inst, "red_moon", 0.30, 0.0)
    assert is_achieved(inst, now)
    assert push_target(inst, now)[1] == pytest.approx([0.30, 0.0])


def _b2brel(direction="up", target=(0.4, 0.0)):
    start = scene(red_moon=(0.3, 0.15), blue_cube=target)
    goal = {"block": "red_moon", "target_block": "blue_cube", "direction": direction}
    return make(fam.B2B_RELATIVE, goal, B2BREL_WORDS, start)


@pytest.mark.parametrize(
    ("x", "y", "expected"),
    [
        (0.344, 0.0399, True),  # beside the s=0.7 point
        (0.344, 0.0401, False),
        (0.312 - 0.0399, 0.0, True),  # beyond the s=1.1 end
        (0.312 - 0.0401, 0.0, False),
        (0.36 + 0.0399, 0.0, True),  # inside the s=0.5 end
    ],
)
def test_block2block_relative_band(x, y, expected):
    inst = _b2brel()
    assert is_achieved(inst, _moved(inst, "red_moon", x, y)) is expected


@pytest.mark.parametrize(("drag", "expected"), [(0.049, True), (0.051, False)])
def test_block2block_relative_target_may_not_be_dragged(drag, expected):
    inst = _b2brel()
    now = _moved(inst, "blue_cube", 0.4, drag).with_object("red_moon", Pose(0.336, drag, 0.0))
    assert is_achieved(inst, now) is expected


def test_block2block_relative_diagonal_offset_is_unnormalised():
    inst = _b2brel("diagonal_down_right")
    assert fam.b2b_relative_offset("diagonal_down_right") == pytest.approx([0.04, 0.04])
    assert is_achieved(inst, _moved(inst, "red_moon", 0.44, 0.04))


@pytest.mark.parametrize(("dy", "expected"), [(0.124, True), (0.126, False), (0.076, True), (0.074, False)])
def test_separate_threshold(dy, expected):
    start = scene(red_moon=(0.4, 0.05), blue_cube=(0.4, 0.0))
    inst = make(fam.SEPARATE, {"block": "red_moon", "avoid": ["blue_cube"], "avoid_mode": "named"}, SEP_WORDS, start)
    assert not is_achieved(inst, start)
    assert is_achieved(inst, _moved(inst, "red_moon", 0.4, dy)) is expected


def test_separate_target_uses_centroid_of_avoid_blocks():
    start = scene(red_moon=(0.4, 0.0), blue_cube=(0.35, -0.03), green_star=(0.45, -0.03))
    goal = {"block": "red_moon", "avoid": ["blue_cube", "green_star"], "avoid_mode": "named"}
    inst = make(fam.SEPARATE, goal, {**SEP_WORDS, "avoid": "blue cube and green star"}, start)
    block, target = push_target(inst, start)
    assert block == "red_moon"
    assert target == pytest.approx([0.4, -0.03 + 0.1])


def test_push_targets_lie_inside_the_success_region():
    for direction in board.DIRECTIONS:
        inst = _b2brel(direction)
        block, target = push_target(inst, inst.scene)
        assert block == "red_moon"
        assert is_achieved(inst, _moved(inst, block, *target)), direction
    start = scene(red_moon=(0.3, -0.1), blue_cube=(0.3, 0.1))
    b2b = make(fam.BLOCK2BLOCK, {"block": "red_moon", "target_block": "blue_cube"}, B2B_WORDS, start)
    assert push_target(b2b, start)[1] == pytest.approx([0.3, 0.1])
    absolute = make(fam.ABSOLUTE, {"block": "red_moon", "location": "top_right"}, ABS_WORDS, start)
    assert push_target(absolute, start)[1] == pytest.approx(board.LOCATIONS["top_right"])
    assert is_achieved(absolute, _moved(absolute, "red_moon", *board.LOCATIONS["top_right"]))


def test_rebase_recomputes_relative_target_and_rejects_out_of_bounds():
    start = scene(red_moon=(0.45, 0.0), blue_cube=(0.3, -0.15))
    inst = make(fam.RELATIVE, {"block": "red_moon", "direction": "up", "magnitude": "near"}, REL_WORDS, start)
    moved = rebase(inst, _moved(inst, "red_moon", 0.40, 0.05))
    assert moved.goal["target_xy"] == pytest.approx([0.25, 0.05])
    assert moved.instruction == inst.instruction and moved.id == inst.id
    assert rebase(inst, _moved(inst, "red_moon", 0.35, 0.0)) is None  # 0.35 - 0.15 is off the target box


def test_rebase_rejects_missing_blocks_and_out_of_bounds_offsets():
    inst = _b2brel("up", target=(0.4, 0.0))
    assert rebase(inst, inst.scene) == inst
    gone = inst.scene.__class__(objects={"red_moon": inst.scene.objects["red_moon"]}, robot=inst.scene.robot)
    assert rebase(inst, gone) is None
    assert rebase(inst, _moved(inst, "blue_cube", 0.30, 0.0)) is None  # 0.30 - 0.08 <= 0.23


def test_rebase_separate_named_needs_neighbours_and_group_rebinds():
    start = scene(red_moon=(0.4, 0.05), blue_cube=(0.4, 0.0))
    named = make(fam.SEPARATE, {"block": "red_moon", "avoid": ["blue_cube"], "avoid_mode": "named"}, SEP_WORDS, start)
    assert rebase(named, _moved(named, "red_moon", 0.4, 0.09)) is None  # already apart: nothing to separate
    clump = scene(
        red_moon=(0.4, 0.0),
        blue_cube=(0.4, 0.05),
        green_star=(0.4, -0.05),
        yellow_star=(0.35, 0.0),
        red_pentagon=(0.3, 0.2),
    )
    words = {**SEP_WORDS, "avoid": "group"}
    group = make(fam.SEPARATE, {"block": "red_moon", "avoid": [], "avoid_mode": "group"}, words, clump)
    assert sorted(group.goal["avoid"]) == ["blue_cube", "green_star", "yellow_star"]
    joined = rebase(group, clump.with_object("red_pentagon", Pose(0.45, 0.0, 0.0)))
    assert sorted(joined.goal["avoid"]) == ["blue_cube", "green_star", "red_pentagon", "yellow_star"]
    assert rebase(group, clump.with_object("yellow_star", Pose(0.25, 0.0, 0.0))) is None  # only two left


def test_missing_block_is_not_achieved():
    inst = _b2brel()
    assert not is_achieved(inst, inst.scene.__class__(objects={}, robot=None))
