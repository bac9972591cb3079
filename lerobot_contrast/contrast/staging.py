"""Staging: the concrete instance a planned trial runs, given the scene the robot left behind, what the operator
moves to set it up, and the robots that can read and stage a scene themselves."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from lerobot_contrast.contrast.cost import moved_objects
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.task import Task, perturb


@dataclass(frozen=True)
class Staged:
    """A materialised trial: the instance to run (None if not applicable) and how it was staged."""

    instance: Instance | None
    staging: str  # "reset" | "in_place" | "not_applicable"


def trial_rng(seed: int, index: int) -> np.random.Generator:
    """Per-trial randomness, independent of history, so a resumed run draws exactly what it would have."""
    return np.random.default_rng([seed, index])


def materialize(
    trial: PlannedTrial, task: Task, current: Scene, previous: Staged | None, rng: np.random.Generator
) -> Staged:
    """The instance `trial` runs when the robot left the scene as `current`."""
    if trial.repeat > 0 and previous is not None:
        return previous
    if trial.staging == "reset" or previous is None:  # the session's first scene is always staged in full
        return Staged(trial.base, "reset")
    if trial.perturbation is None:
        here = task.rebase(trial.base, current)
        if here is None or task.is_achieved(here, current):
            return Staged(trial.base, "reset")
        return Staged(here, "in_place")
    perturbation = task.perturbations.get(trial.perturbation)
    perturbed = perturb(task, perturbation, trial.base.derive(scene=current), rng)
    if perturbed is None:
        return Staged(None, "not_applicable")
    return Staged(perturbed, "in_place")


@dataclass(frozen=True)
class Move:
    """One object the operator moves before a trial."""

    name: str
    start: Pose | None
    end: Pose | None
    distance: float


def staging_moves(current: Scene, target: Scene, tolerance: float = 0.005) -> list[Move]:
    """What the operator must move to go from `current` to `target`, largest move first."""
    moves = [
        Move(name, current.objects.get(name), target.objects.get(name), distance)
        for name, distance in moved_objects(current, target, tolerance).items()
    ]
    return sorted(moves, key=lambda m: -m.distance)


@runtime_checkable
class SceneIO(Protocol):
    """A robot (simulated, or with a perception stack) that can report and set its scene.

    The runner then stages scenes and judges predicates without asking the operator. A robot in another package
    may report the scene as its JSON (`Scene.to_json`), so that it need not import this one."""

    def read_scene(self) -> Scene | Mapping[str, Any]: ...

    def stage_scene(self, scene: Scene) -> None: ...


def read_scene(robot: SceneIO) -> Scene:
    """The scene `robot` reports, as a Scene."""
    scene = robot.read_scene()
    return scene if isinstance(scene, Scene) else Scene.from_json(scene)


def reports_scene(robot: Any, objects: Iterable[str] = ()) -> bool:
    """Whether `robot` can read and stage a scene of `objects` now.

    A remote host may report that it cannot (`supports_scene_io`); a simulator places only the objects
    it models (`stageable_objects`)."""
    if not (isinstance(robot, SceneIO) and getattr(robot, "supports_scene_io", True)):
        return False
    stageable = getattr(robot, "stageable_objects", None)
    return stageable is None or set(objects) <= set(stageable)
