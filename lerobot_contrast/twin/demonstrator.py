"""The scripted demonstrator as an evaluator policy (`--policy.type=so101_demonstrator`): on the virtual SO-101 it
reads the trial's goal predicate (what the instruction's words mean, not the words) and the twin's true poses, and
runs the same plan it demonstrates with. It is the contrast set's reference by construction, not a policy that
understands language: against it, a learned policy's losses on the perturbations are the policy's own."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from lerobot_contrast.clock.robot_clock import robot_clock
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.task_file import FileTask
from lerobot_contrast.policies.base import PolicyArgs, PolicyError
from lerobot_contrast.so101 import DEFAULT_PACE, plan
from lerobot_contrast.twin.placement_client import DEFAULT_ADDRESS, PlacementClient, TwinError


class SO101Demonstrator:
    name = "so101_demonstrator"

    def __init__(self, task: FileTask, placement: str, pace: float) -> None:
        self.task, self.pace = task, pace
        self.model = plan.arm_model(task.spec)
        self.placement = PlacementClient(placement)
        self._true_poses()  # a twin that does not answer is one line before the run starts
        self._schedule: list[tuple[float, dict[str, float]]] = []
        self._start: float | None = None

    def reset(self, context: TrialContext) -> None:
        predicate = context.instance.goal["predicate"]
        self._schedule = plan.schedule(self.model, predicate, self._true_poses(), self.task.spec, self.pace)
        self._start = None

    def _true_poses(self) -> dict[str, tuple[float, float, float, float]]:
        try:
            return self.placement.poses()
        except TwinError as error:
            raise PolicyError(
                f"--policy.type=so101_demonstrator: {error}; start the twin, or give its socket with --policy.options='{{placement: ADDRESS}}'"
            ) from None

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]:
        now = robot_clock().now()
        if self._start is None:  # the episode's clock starts at its first step, as the motion does
            self._start = now
        return plan.goals_at(self._schedule, now - self._start)


def build(args: PolicyArgs, robot: Any, task: Any, rename_map: Mapping[str, str]) -> SO101Demonstrator:
    if not isinstance(task, FileTask) or robot.robot_type != "so_follower":
        raise PolicyError(
            "--policy.type=so101_demonstrator drives an SO-101 (--robot.type=so101_follower, the virtual SO-101) "
            "on a task file's world (--task=so101_blocks, so101_red_left or yours)"
        )
    return SO101Demonstrator(task, args.options.get("placement", DEFAULT_ADDRESS), DEFAULT_PACE)
