"""A trained `vln_navigator` checkpoint as an actor in the apartment: for DAgger rounds and closed-loop checks."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from lerobot_policy_vln_navigator.configuration_vln_navigator import COMMANDS, DEPTH_KEY

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.training.nav_episodes import IMAGE_KEY, NavSimulator


class NavLearner:
    """The policy saved at `path`, fed the simulator's camera frame, state and the instance's instruction."""

    def __init__(self, path: Path | str) -> None:
        from lerobot_policy_vln_navigator import VLNNavigatorPolicy

        self.policy = VLNNavigatorPolicy.from_pretrained(str(path), device="cpu").eval()
        self.instruction = ""

    def reset(self, instance: Instance) -> None:
        self.policy.reset()
        self.instruction = instance.instruction

    def batch(self, observation: dict[str, Any]) -> dict[str, Any]:
        """What LeRobot's pre-processor hands the policy: a float image in [0, 1], depth in metres, the state, the
        instruction."""
        return {
            IMAGE_KEY: torch.from_numpy(observation["image"]).permute(2, 0, 1).unsqueeze(0).float() / 255,
            DEPTH_KEY: torch.from_numpy(observation["depth"])[None, None].float(),
            "observation.state": torch.from_numpy(observation["state"]).unsqueeze(0),
            "task": [self.instruction],
        }

    def act(self, observation: dict[str, Any], label: str | None = None) -> str:
        return COMMANDS[int(self.policy.select_action(self.batch(observation))[0].argmax())]


@dataclass
class NavMixture:
    """DAgger's actor: the teacher's command with probability `beta` at each step, the learner's otherwise."""

    learner: NavLearner
    beta: float
    rng: np.random.Generator

    def reset(self, instance: Instance) -> None:
        self.learner.reset(instance)

    def act(self, observation: dict[str, Any], label: str) -> str:
        own = self.learner.act(observation)  # always called, so the policy's memory follows the episode
        return label if self.rng.random() < self.beta else own


def closed_loop(actor, simulator: NavSimulator, instances: list[Instance], max_steps: int) -> dict[str, float]:
    """Success, progress and SPL of `actor` alone on `instances`."""
    outcomes = [simulator.rollout(instance, actor, max_steps) for instance in instances]
    return {
        "success": float(np.mean([o.success for o in outcomes])),
        "progress": float(np.mean([o.progress for o in outcomes])),
        "spl": float(np.mean([o.spl for o in outcomes])),
    }


def select_action_ms(learner: NavLearner, instance: Instance) -> float:
    """Median wall time of one `select_action` on one CPU thread, on a full-size (640 x 480) camera frame already
    converted to float by LeRobot's pre-processor (as `predict_action` hands it over)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        observation = {
            "image": np.random.default_rng(0).integers(0, 255, (480, 640, 3), dtype=np.uint8),
            "depth": np.random.default_rng(1).uniform(0.3, 6.0, (480, 640)).astype(np.float32),
            "state": np.zeros(6, np.float32),
        }
        learner.reset(instance)
        batch = learner.batch(observation)
        times = []
        for _ in range(50):
            start = time.perf_counter()
            learner.policy.select_action(batch)
            times.append(time.perf_counter() - start)
        return float(np.median(times) * 1000)
    finally:
        torch.set_num_threads(threads)
