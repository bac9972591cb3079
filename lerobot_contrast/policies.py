"""Policy adapters: what the evaluation loop drives. Scripted baselines for the simulator live here."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.sims.language_table.oracle import PushOracle
from lerobot_contrast.tasks.language_table.board import MAX_ACTION


class Policy(Protocol):
    name: str

    def reset(self, instance: Instance, rng: np.random.Generator) -> None:
        """Start an episode of `instance`; `rng` is this trial's own randomness (reproducible on resume)."""
        ...

    def act(self, observation: Mapping[str, Any]) -> np.ndarray: ...


class OraclePolicy:
    """The scripted push oracle with privileged access to the simulator's state.

    `noise_std` adds Gaussian noise (metres) to every action. `language_blind` is the probability,
    drawn once per episode, that the oracle ignores the words of a perturbed instruction: it then
    executes its base instance's instruction re-grounded in the current scene (and stays still
    where that instruction is already satisfied). It therefore fails ΔLB trials whose behaviour
    differs from the base, while ΔL, ΔS and ΔSB trials, whose instruction means the same as the
    base's, are unaffected.
    """

    name = "oracle"

    def __init__(
        self, env: Any, task: Any, bases: Mapping[str, Instance], noise_std: float = 0.0, language_blind: float = 0.0
    ) -> None:
        if noise_std < 0:
            raise UserError(f"--policy.noise_std must be >= 0, got {noise_std}")
        if not 0.0 <= language_blind <= 1.0:
            raise UserError(f"--policy.language_blind must be a probability in [0, 1], got {language_blind}")
        self.env = env
        self.task = task
        self.bases = bases
        self.noise_std = noise_std
        self.language_blind = language_blind
        self._oracle: PushOracle | None = None

    def reset(self, instance: Instance, rng: np.random.Generator) -> None:
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

    def act(self, observation: Mapping[str, Any]) -> np.ndarray:
        if self._oracle is None:
            return np.zeros(2, dtype=np.float32)
        scene = self.env.unwrapped.scene()
        return self._oracle.act(scene, observation["effector_target_translation"])


class RandomPolicy:
    """Uniform random actions: a floor that any useful policy must beat."""

    name = "random"

    def __init__(self, scale: float = MAX_ACTION) -> None:
        self.scale = scale
        self._rng = np.random.default_rng(0)

    def reset(self, instance: Instance, rng: np.random.Generator) -> None:
        self._rng = rng

    def act(self, observation: Mapping[str, Any]) -> np.ndarray:
        return self._rng.uniform(-self.scale, self.scale, size=2).astype(np.float32)
