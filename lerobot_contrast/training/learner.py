"""A trained `tabletop_pointer` checkpoint as an actor in the simulator: for DAgger rounds and closed-loop checks,
several episodes side by side (lanes) answered in one call per step."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.lanes.choice import AUTO_LANES as LANES
from lerobot_contrast.training.episodes import Simulator, side_by_side


class Learner:
    """The policy saved at `path`, fed the simulator's camera frame, state and the instance's instruction. It acts
    through the policy's `lane_step`, for one episode or several side by side (lanes), with the same actions."""

    def __init__(self, path: Path | str) -> None:
        from lerobot_policy_tabletop_pointer import TabletopPointerPolicy

        self.policy = TabletopPointerPolicy.from_pretrained(str(path), device="cpu").eval()
        self.instructions: dict[int, str] = {}
        self.memories: dict[int, dict[str, Any]] = {}

    def reset(self, instance: Instance) -> None:
        self.start(0, instance, 0)

    def act(self, observation: dict[str, Any], label: np.ndarray | None = None) -> np.ndarray:
        return self.act_lanes([0], [observation])[0]

    def start(self, lane: int, instance: Instance, index: int = 0) -> None:
        self.instructions[lane], self.memories[lane] = instance.instruction, {}

    def act_lanes(
        self, lanes: Sequence[int], observations: Sequence[dict[str, Any]], labels: Sequence[Any] = ()
    ) -> list[np.ndarray]:
        batch = self.batch(observations, [self.instructions[lane] for lane in lanes])
        with torch.inference_mode():
            actions = self.policy.lane_step(batch, [self.memories[lane] for lane in lanes])
        return [row.numpy().astype(np.float64) for row in actions]

    @staticmethod
    def batch(observations: Sequence[dict[str, Any]], instructions: Sequence[str]) -> dict[str, Any]:
        images = [torch.from_numpy(o["image"]).permute(2, 0, 1).unsqueeze(0).float() / 255 for o in observations]
        return {
            "observation.images.top": torch.cat(images),
            "observation.state": torch.stack([torch.from_numpy(o["state"]) for o in observations]),
            "task": list(instructions),
        }


@dataclass
class Mixture:
    """DAgger's actor: the oracle's action with probability `beta` at each step, the learner's otherwise. Each
    episode draws from its own generator (seeded from `rng` in the episodes' order), so lanes draw as one lane."""

    learner: Learner
    beta: float
    rng: np.random.Generator
    draws: dict[int, np.random.Generator] = field(default_factory=dict)

    def reset(self, instance: Instance) -> None:
        self.start(0, instance, 0)

    def act(self, observation: dict[str, Any], label: np.ndarray) -> np.ndarray:
        return self.act_lanes([0], [observation], [label])[0]

    def start(self, lane: int, instance: Instance, index: int = 0) -> None:
        self.learner.start(lane, instance)
        self.draws[lane] = np.random.default_rng(self.rng.integers(2**63))

    def act_lanes(
        self, lanes: Sequence[int], observations: Sequence[dict[str, Any]], labels: Sequence[np.ndarray]
    ) -> list[np.ndarray]:
        own = self.learner.act_lanes(lanes, observations)  # always asked, so the policy's episode state follows
        return [
            label if self.draws[lane].random() < self.beta else action
            for lane, label, action in zip(lanes, labels, own, strict=True)
        ]


def closed_loop(
    learner: Learner, simulator: Simulator, instances: list[Instance], max_steps: int, lanes: int = LANES
) -> dict[str, float]:
    """Success of the learner alone on `instances`: overall and per family (`success_<family>`); `lanes` episodes
    run side by side, with the outcomes of one lane."""
    wins: Counter[str] = Counter()
    totals: Counter[str] = Counter()
    for instance, outcome in zip(instances, side_by_side(learner, simulator, instances, max_steps, lanes), strict=True):
        wins[instance.family] += outcome.success
        totals[instance.family] += 1
    figures = {"success": sum(wins.values()) / max(1, sum(totals.values()))}
    figures.update({f"success_{family}": wins[family] / totals[family] for family in sorted(totals)})
    return figures
