"""The policy interface the runner drives, and the scripted baselines for the simulated tabletop.

A policy maps a robot observation (LeRobot's flat dict) to a robot action dict. LeRobot
`PreTrainedPolicy`s are wrapped into this interface by `pretrained_policy.py`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.runners.episode import TrialContext
from lerobot_contrast.sims.language_table.oracle import PushOracle


class Policy(Protocol):
    name: str

    def reset(self, context: TrialContext) -> None:
        """Start an episode of `context.instance`; `context.rng` is this trial's own randomness."""
        ...

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]: ...


class OraclePolicy:
    """The scripted push oracle, with privileged access to the simulator's block poses through `read_scene`.

    `noise_std` adds Gaussian noise (metres) to every action. `language_blind` is the probability,
    drawn once per episode, that the oracle ignores the words of a perturbed instruction: it then
    executes its base instance's instruction re-grounded in the current scene (and stays still
    where that instruction is already satisfied). It therefore fails ΔLB trials whose behaviour
    differs from the base, while ΔL, ΔS and ΔSB trials, whose instruction means the same as the
    base's, are unaffected.
    """

    name = "oracle"

    def __init__(
        self,
        read_scene: Callable[[], Scene],
        task: Any,
        bases: Mapping[str, Instance],
        noise_std: float = 0.0,
        language_blind: float = 0.0,
    ) -> None:
        if noise_std < 0:
            raise UserError(f"--policy.noise_std must be >= 0, got {noise_std}")
        if not 0.0 <= language_blind <= 1.0:
            raise UserError(f"--policy.language_blind must be a probability in [0, 1], got {language_blind}")
        self.read_scene = read_scene
        self.task = task
        self.bases = bases
        self.noise_std = noise_std
        self.language_blind = language_blind
        self._oracle: PushOracle | None = None

    def reset(self, context: TrialContext) -> None:
        instance, rng = context.instance, context.rng
        goal: Instance | None = instance
        blind = rng.random() < self.language_blind
        if blind and instance.perturbation is not None and instance.base_id in self.bases:
            goal = self.task.rebase(self.bases[instance.base_id], instance.scene)
            if goal is not None and self.task.is_achieved(goal, instance.scene):
                goal = None
        self._oracle = None
        if goal is not None:
            self._oracle = PushOracle(self.task, noise_std=self.noise_std, rng=rng)
            self._oracle.reset(goal)

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]:
        if self._oracle is None:
            return {"delta_x": 0.0, "delta_y": 0.0}
        target = (observation["effector_target.x"], observation["effector_target.y"])
        dx, dy = self._oracle.act(self.read_scene(), target)
        return {"delta_x": float(dx), "delta_y": float(dy)}


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
