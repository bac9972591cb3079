"""Test instances: (instruction, scene, goal) with the i.i.d. instance they derive from."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from lerobot_contrast.contrast.scene import Scene


@dataclass(frozen=True)
class Instance:
    """One test instance.

    `goal` is task-specific, JSON-serialisable, and says what counts as the expected behaviour
    (for Language-Table: the block to push and where). `perturbation` is None for an original
    i.i.d. instance, else the name of the perturbation that produced it from `base_id`.
    """

    id: str
    family: str
    instruction: str
    scene: Scene
    goal: Mapping[str, Any] = field(default_factory=dict)
    base_id: str = ""
    perturbation: str | None = None

    def __post_init__(self) -> None:
        if not self.base_id:
            object.__setattr__(self, "base_id", self.id)

    def derive(self, **changes: Any) -> Instance:
        """A copy with `changes`; keeps `base_id` so derived instances stay clustered with their base."""
        return replace(self, **changes)

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "family": self.family,
            "instruction": self.instruction,
            "scene": self.scene.to_json(),
            "goal": dict(self.goal),
            "base_id": self.base_id,
            "perturbation": self.perturbation,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Instance:
        return cls(
            id=data["id"],
            family=data["family"],
            instruction=data["instruction"],
            scene=Scene.from_json(data["scene"]),
            goal=dict(data.get("goal", {})),
            base_id=data.get("base_id", ""),
            perturbation=data.get("perturbation"),
        )
