"""A trained `tabletop_pointer` checkpoint as an actor in the simulator: for DAgger rounds and closed-loop checks."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.training.episodes import Simulator


class Learner:
    """The policy saved at `path`, fed the simulator's camera frame, state and the instance's instruction."""

    def __init__(self, path: Path | str) -> None:
        from lerobot_policy_tabletop_pointer import TabletopPointerPolicy

        self.policy = TabletopPointerPolicy.from_pretrained(str(path), device="cpu").eval()
        self.instruction = ""

    def reset(self, instance: Instance) -> None:
        self.policy.reset()
        self.instruction = instance.instruction

    def act(self, observation: dict[str, Any], label: np.ndarray | None = None) -> np.ndarray:
        image = torch.from_numpy(observation["image"]).permute(2, 0, 1).unsqueeze(0).float() / 255
        batch = {
            "observation.images.top": image,
            "observation.state": torch.from_numpy(observation["state"]).unsqueeze(0),
            "task": [self.instruction],
        }
        return self.policy.select_action(batch)[0].numpy().astype(np.float64)


@dataclass
class Mixture:
    """DAgger's actor: the oracle's action with probability `beta` at each step, the learner's otherwise."""

    learner: Learner
    beta: float
    rng: np.random.Generator

    def reset(self, instance: Instance) -> None:
        self.learner.reset(instance)

    def act(self, observation: dict[str, Any], label: np.ndarray) -> np.ndarray:
        own = self.learner.act(observation)  # always called, so the policy's per-episode state follows the episode
        return label if self.rng.random() < self.beta else own


def closed_loop(learner: Learner, simulator: Simulator, instances: list[Instance], max_steps: int) -> dict[str, float]:
    """Success of the learner alone on `instances`: overall and per family (`success_<family>`)."""
    wins: Counter[str] = Counter()
    totals: Counter[str] = Counter()
    for instance in instances:
        outcome = simulator.rollout(instance, learner, max_steps)
        wins[instance.family] += outcome.success
        totals[instance.family] += 1
    figures = {"success": sum(wins.values()) / max(1, sum(totals.values()))}
    figures.update({f"success_{family}": wins[family] / totals[family] for family in sorted(totals)})
    return figures
