"""Execute trials in a gymnasium simulator: reset to the instance, roll the policy out, report the outcome."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.trial import Outcome
from lerobot_contrast.policies import Policy
from lerobot_contrast.runners.episode import TrialContext

ReferenceFn = Callable[[Instance], float | None]


class SimRunner:
    """Runs one instance per call in `env`, which must accept `reset(options={"instance": ...})`
    and expose `scene()` on its unwrapped env (the scene the robot leaves behind)."""

    def __init__(self, env: gym.Env, policy: Policy, max_steps: int, reference: ReferenceFn | None = None) -> None:
        self.env = env
        self.policy = policy
        self.max_steps = max_steps
        self.reference = reference

    def __call__(self, context: TrialContext) -> Outcome:
        instance, rng = context.instance, context.rng
        start = time.perf_counter()
        observation, info = self.env.reset(seed=int(rng.integers(2**31)), options={"instance": instance})
        self.policy.reset(instance, rng)
        position = np.asarray(observation["effector_translation"], dtype=np.float64)
        path_length, steps = 0.0, 0
        success = bool(info.get("is_success", False))
        while not success and steps < self.max_steps:
            observation, _, terminated, truncated, info = self.env.step(self.policy.act(observation))
            steps += 1
            new_position = np.asarray(observation["effector_translation"], dtype=np.float64)
            path_length += float(np.hypot(*(new_position - position)))
            position = new_position
            success = bool(info.get("is_success", False))
            if terminated or truncated:
                break
        scene_after = self.env.unwrapped.scene()
        duration = time.perf_counter() - start
        reference = None if self.reference is None else self.reference(instance)
        return Outcome(
            success=success,
            steps=steps,
            path_length=path_length,
            scene_after=scene_after,
            duration_s=duration,
            reference_length=reference,
            extra=_extra(info),
        )


def _extra(info: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in info.items() if isinstance(v, (bool, int, float, str)) and k != "is_success"}
