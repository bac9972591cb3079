"""The camera's verdict on a trial: the task's own goal check on the scene the camera saw, and whether it is sure,
that is whether the verdict holds however each object it names is shifted by up to the camera's uncertainty."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene

DIRECTIONS = 16  # shifts tried around each named object: a boundary within the band is found to 2 % of it
RING_M = 0.005  # and at every 5 mm out to the band: a band wider than a goal's region would step over it


@dataclass(frozen=True)
class Verdict:
    success: bool
    sure: bool
    why: str  # what makes it unsure ("" when sure)


def named_objects(instance: Instance) -> list[str]:
    """The objects the goal names (its subject and the object it is judged against)."""
    predicate = instance.goal.get("predicate") or {}
    return [predicate[key] for key in ("subject", "near") if key in predicate]


def verdict(
    achieved: Callable[[Instance, Scene], bool],
    instance: Instance,
    scene: Scene,
    unseen: tuple[str, ...],
    held: tuple[str, ...],
    uncertainty: float,
) -> Verdict:
    """Judge `scene` (what the camera saw) with `achieved`; unsure where a named object was not seen, or where
    shifting one by up to `uncertainty` metres in some direction turns the verdict."""
    named = named_objects(instance)
    missing = [name for name in named if name in unseen]
    if missing:
        return Verdict(False, False, f"{', '.join(missing)} not seen")
    if any(name in held for name in named):  # in the jaws, not put down: a failure wherever it hangs
        return Verdict(False, True, "")
    success = achieved(instance, scene)
    rings = max(1, math.ceil(uncertainty / RING_M))
    for name in named:
        pose = scene.objects[name]
        for k, ring in itertools.product(range(DIRECTIONS), range(1, rings + 1)):
            angle, shift = 2 * math.pi * k / DIRECTIONS, uncertainty * ring / rings
            moved = Pose(pose.x + shift * math.cos(angle), pose.y + shift * math.sin(angle), pose.yaw)
            if achieved(instance, Scene({**scene.objects, name: moved}, scene.robot)) != success:
                return Verdict(success, False, f"{name} is within {uncertainty * 100:g} cm of the goal's boundary")
    return Verdict(success, True, "")
