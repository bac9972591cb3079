"""`--policy.noise_std` for a LeRobot policy: Gaussian noise on every action value it sends, in the action's own
units (metres on the simulated tabletop). It makes a noisier copy of a learned policy, the usual thing to tell apart
from the original in a sequential comparison. The noise comes from the trial's own randomness, so a run and its
resume draw the same noise."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.policies.base import Policy


class NoisyPolicy:
    def __init__(self, policy: Policy, noise_std: float) -> None:
        self.policy, self.noise_std = policy, noise_std
        self.name = policy.name
        self.rng = np.random.default_rng(0)

    def reset(self, context: TrialContext) -> None:
        self.rng = context.rng
        self.policy.reset(context)

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]:
        action = self.policy.act(observation)
        noise = self.rng.normal(0.0, self.noise_std, len(action))
        return {key: float(value) + float(n) for (key, value), n in zip(action.items(), noise, strict=True)}
