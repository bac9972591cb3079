"""The task base class: what a task domain provides to plan and score a contrast-set evaluation, and `perturb`."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Literal

import numpy as np

from lerobot_contrast.contrast.cost import CostModel, make_cost_model
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import Perturbation, PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene

# How a task's outcomes are judged (its `outcome` attribute):
#   "predicate": from the scene the robot left behind (needs a robot that reports its scene), else the operator;
#   "label": the operator says success or failure;
#   "subgoals": the operator says how many of `task.subgoals(instance)` were reached, in order.
OutcomeMode = Literal["predicate", "label", "subgoals"]
OUTCOME_MODES: tuple[OutcomeMode, ...] = ("predicate", "label", "subgoals")


@dataclass(frozen=True)
class Judgement:
    """How an episode went: success, and the fraction of subgoals reached where the task has several."""

    success: bool
    progress: float | None = None


def named_goal_position(instance: Instance) -> tuple[float, float] | None:
    """A goal's `target_xy`, else the pose of the object its `target_block`, `target` or `goal_object` names; None
    when the goal names no place."""
    goal = instance.goal
    if "target_xy" in goal:
        x, y = goal["target_xy"][:2]
        return float(x), float(y)
    for key in ("target_block", "target", "goal_object"):
        pose = instance.scene.objects.get(goal.get(key)) if isinstance(goal.get(key), str) else None
        if pose is not None:
            return pose.x, pose.y
    return None


class Task(ABC):
    """A task domain: samples i.i.d. instances, grounds them in scenes, and judges outcomes.

    A subclass sets `name` and `perturbations` and implements the four abstract methods; every other member
    has a default that suits a single-goal task judged from the scene, and can be overridden (as Gymnasium's
    `Env` does for its optional members). Register a task by name with the `lerobot_contrast.tasks` entry point.
    """

    name: str = "task"
    perturbations: PerturbationRegistry
    # How outcomes are judged (see OUTCOME_MODES).
    outcome: OutcomeMode = "predicate"
    # Base instances an evaluation samples when --n_instances is not given.
    default_instances: int = 50

    @abstractmethod
    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` i.i.d. evaluation instances, each with a valid, not yet achieved goal."""

    @abstractmethod
    def storage_scene(self) -> Scene:
        """Where the objects are before the session's first trial, so that trial pays for a full set-up."""

    @abstractmethod
    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        """The same instruction set in `scene`, with scene-derived goal fields recomputed.

        None when the instruction cannot be grounded there (an object missing, a target off
        the workspace). Achievement is checked separately with `is_achieved`.
        """

    @abstractmethod
    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        """Whether `scene` satisfies the instance's goal, given that it started in `instance.scene`."""

    def subgoals(self, instance: Instance) -> list[str]:
        """The instance's ordered subgoals, as the operator is asked about them (default: none)."""
        return []

    def judge(self, instance: Instance, path: list[Pose], scene_after: Scene) -> Judgement:
        """Judge an episode from the robot's planar path and final scene (default: `is_achieved` on the scene)."""
        return Judgement(success=self.is_achieved(instance, scene_after))

    def reference_length(self, instance: Instance) -> float | None:
        """The length of a reference (shortest or demonstrated) path for SPL (default: none, so no SPL)."""
        return None

    def path_metrics(self, instance: Instance, path: list[Pose]) -> dict[str, float | None]:
        """Task-specific metrics of the robot's path (e.g. nDTW for navigation), recorded with the trial."""
        return {}

    def goal_position(self, instance: Instance) -> tuple[float, float] | None:
        """Where the instruction wants the robot or an object to end up, for drawing the goal on a map.

        Default: `named_goal_position`."""
        return named_goal_position(instance)

    def cost_model(self, name: str) -> CostModel:
        """The `--cost` model by name (default: the core's distance or reset-time model)."""
        return make_cost_model(name)


def perturb(task: Task, perturbation: Perturbation, instance: Instance, rng: np.random.Generator) -> Instance | None:
    """Apply `perturbation` to `instance` (set in the current scene) and check the result is a valid test.

    Returns None when the perturbation does not apply, when the task cannot ground the result in
    its scene (a target off the board, a missing object), or when the expected behaviour is
    already achieved there (a trial the robot would pass by doing nothing).
    """
    out = perturbation.apply(instance, rng)
    if out is None:
        return None
    if perturbation.axis in ("L", "LB") and out.scene != instance.scene:
        raise ValueError(f"language perturbation {perturbation.name!r} changed the scene")
    out = task.rebase(out, out.scene)
    if out is None or task.is_achieved(out, out.scene):
        return None
    return out.derive(
        id=f"{instance.base_id}/{perturbation.name}",
        base_id=instance.base_id,
        perturbation=perturbation.name,
    )
