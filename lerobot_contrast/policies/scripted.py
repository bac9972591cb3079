"""A scripted baseline for any robot with a planar end-effector delta action: uniform random actions."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.policies.base import PolicyArgs, check_tabletop

if TYPE_CHECKING:
    from lerobot.robots import Robot


def build(args: PolicyArgs, robot: Robot, task: Task, rename_map: Mapping[str, str]) -> RandomPolicy:
    from lerobot_contrast.domains.language_table.board import MAX_ACTION

    check_tabletop("random", robot)
    return RandomPolicy(list(robot.action_features), MAX_ACTION)


class RandomPolicy:
    """Uniform random actions in [-scale, scale] on every action key: a floor any useful policy must beat."""

    name = "random"

    def __init__(self, action_keys: list[str], scale: float) -> None:
        self.action_keys = action_keys
        self.scale = scale
        self._rng = np.random.default_rng(0)

    def reset(self, context: TrialContext) -> None:
        self._rng = context.rng

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]:
        values = self._rng.uniform(-self.scale, self.scale, size=len(self.action_keys))
        return dict(zip(self.action_keys, values.tolist(), strict=True))
