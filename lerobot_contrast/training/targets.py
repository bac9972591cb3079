"""Privileged training targets of one Language-Table frame: where every block is, which one the instruction pushes,
and how its goal is built (anchor blocks or the board origin, an offset, a keep-away distance).

They are the `observation.privileged.*` features of the demonstration dataset; the `tabletop_pointer` policy
learns them from pixels and words and never receives them at evaluation.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.oracle import reachable

OBJECTS = board.ALL_BLOCKS
PREFIX = "observation.privileged."
K = len(OBJECTS)
SHAPES = {
    "objects_xy": (2 * K,),
    "objects_present": (K,),
    "source": (K,),
    "anchor": (K + 1,),  # the last entry is the board origin
    "offset": (2,),
    "away": (1,),
    "group": (1,),
    "goal_xy": (2,),
}


def features() -> dict[str, dict[str, Any]]:
    """LeRobotDataset feature entries of the privileged targets."""
    return {PREFIX + name: {"dtype": "float32", "shape": shape, "names": None} for name, shape in SHAPES.items()}


def _one_hot(names: list[str], size: int = K) -> np.ndarray:
    out = np.zeros(size, np.float32)
    for name in names:
        out[OBJECTS.index(name)] = 1.0 / len(names)
    return out


def oracle_goal(instance: Instance, scene: Scene) -> np.ndarray:
    """Where the push oracle takes the block: the family's push target, kept where the effector fits behind it."""
    return reachable(fam.push_target(instance, scene)[1])


def _goal_structure(instance: Instance, goal_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(anchor weights, offset, away distance, group flag) such that the goal is anchor + offset (+ away)."""
    goal, family = instance.goal, instance.family
    if family == fam.BLOCK2BLOCK:
        return _one_hot([goal["target_block"]], K + 1), np.zeros(2), 0.0, 0.0
    if family == fam.B2B_RELATIVE:
        offset = fam.b2b_relative_offset(goal["direction"]) * board.B2B_RELATIVE_PUSH_SCALE
        return _one_hot([goal["target_block"]], K + 1), offset, 0.0, 0.0
    if family == fam.RELATIVE:  # measured from where the block stood when the instruction was given
        start = instance.scene.objects[goal["block"]]
        return _one_hot([goal["block"]], K + 1), goal_xy - (start.x, start.y), 0.0, 0.0
    if family == fam.ABSOLUTE:
        origin = np.zeros(K + 1, np.float32)
        origin[K] = 1.0
        return origin, goal_xy, 0.0, 0.0
    if family == fam.SEPARATE:
        group = 1.0 if goal["avoid_mode"] == "group" else 0.0
        return _one_hot(list(goal["avoid"]), K + 1), np.zeros(2), board.SEPARATE_MAGNITUDE, group
    raise ValueError(f"unknown Language-Table family {family!r}")


def frame_targets(instance: Instance, scene: Scene) -> dict[str, np.ndarray]:
    """The privileged features of a frame showing `scene` while `instance` is being executed."""
    xy = np.zeros((K, 2), np.float32)
    present = np.zeros(K, np.float32)
    for name, pose in scene.objects.items():
        i = OBJECTS.index(name)
        xy[i], present[i] = (pose.x, pose.y), 1.0
    goal_xy = oracle_goal(instance, scene)
    anchor, offset, away, group = _goal_structure(instance, goal_xy)
    values = {
        "objects_xy": xy.reshape(-1),
        "objects_present": present,
        "source": _one_hot([instance.goal["block"]]),
        "anchor": anchor,
        "offset": offset,
        "away": [away],
        "group": [group],
        "goal_xy": goal_xy,
    }
    return {PREFIX + name: np.asarray(v, np.float32).reshape(SHAPES[name]) for name, v in values.items()}
