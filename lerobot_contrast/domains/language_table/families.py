"""The five evaluation families: grounding a goal in a scene, success predicates, and push targets.
All thresholds are the benchmark's reward thresholds (see board.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table.geometry import inside_target_bounds

BLOCK2BLOCK = "block2block"
ABSOLUTE = "block2absolutelocation"
RELATIVE = "block2relativelocation"
B2B_RELATIVE = "block2blockrelativelocation"
SEPARATE = "separate"
FAMILIES = (BLOCK2BLOCK, ABSOLUTE, RELATIVE, B2B_RELATIVE, SEPARATE)
# A "group"/"clump" needs at least this many blocks; the benchmark uses group words from three avoid blocks on.
MIN_GROUP_SIZE = 3

_B2B_SCALES = np.linspace(*board.B2B_RELATIVE_SCALES)


def _xy(scene: Scene, name: str) -> np.ndarray:
    pose = scene.objects[name]
    return np.array((pose.x, pose.y))


def relative_vector(direction: str, magnitude: str) -> np.ndarray:
    """block2relativelocation: unit direction times the near/far magnitude."""
    signs = np.array(board.DIRECTION_SIGNS[direction])
    return signs / np.linalg.norm(signs) * board.RELATIVE_MAGNITUDES[magnitude]


def b2b_relative_offset(direction: str) -> np.ndarray:
    """block2blockrelativelocation: un-normalised offset from the target block (cardinal 0.08, diagonal 0.04 each)."""
    size = (
        board.B2B_RELATIVE_DIAGONAL_OFFSET if direction.startswith("diagonal") else board.B2B_RELATIVE_CARDINAL_OFFSET
    )
    return np.array(board.DIRECTION_SIGNS[direction]) * size


def neighbours(scene: Scene, name: str) -> list[str]:
    """Blocks whose centres are closer than the joined threshold to `name`, nearest first."""
    here = scene.objects[name]
    near = [(here.distance_to(p), other) for other, p in scene.objects.items() if other != name]
    return [other for d, other in sorted(near) if d < board.SEPARATE_JOINED_DISTANCE]


def separate_target(scene: Scene, block: str, avoid) -> np.ndarray:
    """centroid(avoid) + 0.1 * unit(block - centroid), from the positions in `scene`."""
    if not avoid:
        raise ValueError(f"separate goal for {block!r} has no blocks to separate it from; rebase it first")
    centroid = np.mean([_xy(scene, name) for name in avoid], axis=0)
    away = _xy(scene, block) - centroid
    norm = float(np.linalg.norm(away))
    # The benchmark adds float32 eps to the norm; on an exact tie we push along +x rather than not at all.
    unit = away / norm if norm > 1e-9 else np.array((1.0, 0.0))
    return centroid + board.SEPARATE_MAGNITUDE * unit


def involved_blocks(goal: Mapping[str, Any]) -> list[str]:
    """The blocks the instruction refers to (pushed block first)."""
    names = [goal["block"]]
    if "target_block" in goal:
        names.append(goal["target_block"])
    return names + list(goal.get("avoid", ()))


def ground(family: str, goal: Mapping[str, Any], scene: Scene) -> dict[str, Any] | None:
    """`goal` with its scene-derived fields recomputed for `scene`; None when it cannot be grounded there.

    separate: named avoid blocks stay as the instruction names them, but each must still be a neighbour of
    the pushed block (else "separate" would mean pulling it back, or nothing); a group word re-binds to
    the pushed block's current neighbours and needs at least MIN_GROUP_SIZE of them.
    """
    goal = dict(goal)
    if family == SEPARATE and goal["avoid_mode"] == "group" and goal["block"] in scene.objects:
        goal["avoid"] = neighbours(scene, goal["block"])
        if len(goal["avoid"]) < MIN_GROUP_SIZE:
            return None
    if any(name not in scene.objects for name in involved_blocks(goal)):
        return None
    if family == RELATIVE:
        target = _xy(scene, goal["block"]) + relative_vector(goal["direction"], goal["magnitude"])
        goal["target_xy"] = [float(target[0]), float(target[1])]
    elif family == B2B_RELATIVE:
        target = _xy(scene, goal["target_block"]) + b2b_relative_offset(goal["direction"])
    elif family == SEPARATE:
        if not set(goal["avoid"]) <= set(neighbours(scene, goal["block"])):
            return None
        target = separate_target(scene, goal["block"], goal["avoid"])
    elif family in (BLOCK2BLOCK, ABSOLUTE):
        return goal
    else:
        raise ValueError(f"unknown Language-Table family {family!r}")
    return goal if inside_target_bounds(target) else None


def rebase(instance: Instance, scene: Scene) -> Instance | None:
    """The same instruction grounded in `scene`, or None when it cannot be grounded there."""
    goal = ground(instance.family, instance.goal, scene)
    return None if goal is None else instance.derive(scene=scene, goal=goal)


def is_achieved(instance: Instance, scene: Scene) -> bool:
    """Whether `scene` satisfies the goal of `instance`, which started in `instance.scene`."""
    goal, family = instance.goal, instance.family
    if any(name not in scene.objects for name in involved_blocks(goal)):
        return False
    block = _xy(scene, goal["block"])
    if family == BLOCK2BLOCK:
        return float(np.linalg.norm(block - _xy(scene, goal["target_block"]))) < board.BLOCK2BLOCK_DISTANCE
    if family == ABSOLUTE:
        limit = board.ABSOLUTE_CENTER_DISTANCE if goal["location"] == "center" else board.ABSOLUTE_LOCATION_DISTANCE
        return float(np.linalg.norm(block - np.array(board.LOCATIONS[goal["location"]]))) < limit
    if family == RELATIVE:
        return float(np.linalg.norm(block - np.array(goal["target_xy"]))) < board.RELATIVE_LOCATION_DISTANCE
    if family == B2B_RELATIVE:
        target = _xy(scene, goal["target_block"])
        start = instance.scene.objects[goal["target_block"]]
        if math.hypot(target[0] - start.x, target[1] - start.y) > board.B2B_RELATIVE_DRAGGED:
            return False
        points = target + _B2B_SCALES[:, None] * b2b_relative_offset(goal["direction"])
        return bool(np.min(np.linalg.norm(points - block, axis=1)) < board.B2B_RELATIVE_DISTANCE)
    if family == SEPARATE:
        target = separate_target(scene, goal["block"], goal["avoid"])
        return float(np.linalg.norm(block - target)) < board.SEPARATE_DISTANCE
    raise ValueError(f"unknown Language-Table family {family!r}")


def push_target(instance: Instance, scene: Scene) -> tuple[str, np.ndarray]:
    """The block a scripted pusher should push now, and the xy to push it to (from the current `scene`)."""
    goal, family = instance.goal, instance.family
    block = goal["block"]
    if family == BLOCK2BLOCK:
        return block, _xy(scene, goal["target_block"])
    if family == ABSOLUTE:
        return block, np.array(board.LOCATIONS[goal["location"]])
    if family == RELATIVE:
        return block, np.array(goal["target_xy"], dtype=float)
    if family == B2B_RELATIVE:
        offset = b2b_relative_offset(goal["direction"]) * board.B2B_RELATIVE_PUSH_SCALE
        return block, _xy(scene, goal["target_block"]) + offset
    if family == SEPARATE:
        return block, separate_target(scene, block, goal["avoid"])
    raise ValueError(f"unknown Language-Table family {family!r}")
