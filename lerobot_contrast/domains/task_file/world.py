"""Scenes of a task file: listed scenes, the storage scene, and placing objects at random in their areas."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.task_file.schema import ListedInstance, ObjectSpec, Region, TaskSpec

PLACE_TRIES = 100  # tries per object before a scene sample starts over
SCENE_TRIES = 50
# Objects wait this far beside the workspace's +y edge when no storage is declared.
STORAGE_GAP_M = 0.1


def fixed(objects: Mapping[str, ObjectSpec]) -> dict[str, Pose]:
    return {name: obj.at for name, obj in objects.items() if obj.at is not None}


def listed_scene(listed: ListedInstance, objects: Mapping[str, ObjectSpec]) -> Scene:
    return Scene({**fixed(objects), **listed.placements}, listed.robot)


def storage_scene(spec: TaskSpec) -> Scene:
    """Fixed objects where they stand, the evaluation set's movable objects in a row beside the workspace."""
    names = spec.placed
    if spec.workspace.storage is not None:
        start, end = spec.workspace.storage
    else:
        (x0, x1), (_, y1) = spec.workspace.area.box
        start, end = (x0, y1 + STORAGE_GAP_M), (x1, y1 + STORAGE_GAP_M)
    fractions = np.linspace(0.0, 1.0, len(names)) if len(names) > 1 else [0.5]
    row = {
        name: Pose(float(start[0] + f * (end[0] - start[0])), float(start[1] + f * (end[1] - start[1])))
        for name, f in zip(names, fractions, strict=True)
    }
    return Scene({**fixed(spec.objects), **row}, spec.workspace.robot_start)


def area(spec: TaskSpec, name: str) -> Region:
    region = spec.objects[name].area
    return spec.workspace.area if region is None else spec.workspace.regions[region]


def random_point(region: Region, rng: np.random.Generator) -> tuple[float, float]:
    if region.center is not None:  # uniform over the disc
        r, angle = region.radius * math.sqrt(rng.uniform()), rng.uniform(0.0, 2 * math.pi)
        return region.center[0] + r * math.cos(angle), region.center[1] + r * math.sin(angle)
    return float(rng.uniform(*region.x)), float(rng.uniform(*region.y))


def free_pose(
    spec: TaskSpec,
    name: str,
    scene: Scene,
    rng: np.random.Generator,
    accept: Callable[[Pose], bool] = lambda pose: True,
    tries: int = PLACE_TRIES,
) -> Pose | None:
    """A pose in `name`'s area at least `min_spacing` from every other object in `scene`, that `accept`s."""
    region, spacing = area(spec, name), spec.workspace.min_spacing
    others = [pose for other, pose in scene.objects.items() if other != name]
    for _ in range(tries):
        x, y = random_point(region, rng)
        pose = Pose(x, y)
        if all(pose.distance_to(o) >= spacing for o in others) and accept(pose):
            return pose
    return None


def sample_scene(spec: TaskSpec, rng: np.random.Generator) -> Scene | None:
    """The evaluation set's movable objects placed at random, apart from each other and the fixed objects."""
    for _ in range(SCENE_TRIES):
        scene = Scene(fixed(spec.objects), spec.workspace.robot_start)
        for name in spec.placed:
            pose = free_pose(spec, name, scene, rng)
            if pose is None:
                break
            scene = scene.with_object(name, pose)
        else:
            return scene
    return None
