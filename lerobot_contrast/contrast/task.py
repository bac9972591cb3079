"""The task protocol: what a task domain provides to plan and score a contrast-set evaluation."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from lerobot_contrast.contrast.cost import CostModel, make_cost_model
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene


class Task(Protocol):
    """A task domain: samples i.i.d. instances, grounds them in scenes, and judges outcomes."""

    name: str
    perturbations: PerturbationRegistry

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` i.i.d. evaluation instances, each with a valid, not yet achieved goal."""
        ...

    def storage_scene(self) -> Scene:
        """Where the objects are before the session's first trial, so that trial pays for a full set-up."""
        ...

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        """The same instruction set in `scene`, with scene-derived goal fields recomputed.

        None when the instruction cannot be grounded there (an object missing, a target off
        the workspace). Achievement is checked separately with `is_achieved`.
        """
        ...

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        """Whether `scene` satisfies the instance's goal, given that it started in `instance.scene`."""
        ...


@dataclass(frozen=True)
class Judgement:
    """How an episode went: success, and the fraction of subgoals reached where the task has several."""

    success: bool
    progress: float | None = None


# How a task's outcomes are judged (its optional `outcome` attribute):
#   "predicate": from the scene the robot left behind (needs a robot that reports its scene), else the operator;
#   "label": the operator says success or failure;
#   "subgoals": the operator says how many of `task.subgoals(instance)` were reached, in order.
OUTCOME_MODES = ("predicate", "label", "subgoals")


def outcome_mode(task: Task) -> str:
    return getattr(task, "outcome", "predicate")


def subgoals(task: Task, instance: Instance) -> list[str]:
    """The instance's ordered subgoals (empty for a single-goal task)."""
    hook = getattr(task, "subgoals", None)
    return [] if hook is None else list(hook(instance))


def judge(task: Task, instance: Instance, path: list[Pose], scene_after: Scene) -> Judgement:
    """Judge an episode from the robot's planar path and final scene.

    A task may define `judge(instance, path, scene_after) -> Judgement` (e.g. ordered subgoals along a
    navigation path); otherwise success is `is_achieved` on the final scene."""
    hook = getattr(task, "judge", None)
    if hook is not None:
        return hook(instance, path, scene_after)
    return Judgement(success=task.is_achieved(instance, scene_after))


def reference_length(task: Task, instance: Instance) -> float | None:
    """The length of a reference (shortest or demonstrated) path for SPL, when the task can compute one."""
    hook = getattr(task, "reference_length", None)
    return None if hook is None else hook(instance)


def path_metrics(task: Task, instance: Instance, path: list[Pose]) -> dict[str, float]:
    """Task-specific metrics of the robot's path (e.g. nDTW for navigation), recorded with the trial."""
    hook = getattr(task, "path_metrics", None)
    return {} if hook is None else {k: v for k, v in hook(instance, path).items() if v is not None}


def cost_model(task: Task, name: str) -> CostModel:
    """The `--cost` model: the task's own (a task file may declare handling times), else the default one."""
    hook = getattr(task, "cost_model", None)
    return make_cost_model(name) if hook is None else hook(name)
