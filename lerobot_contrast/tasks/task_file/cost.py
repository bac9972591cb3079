"""A task file's cost models: distance moved (with its tolerance and add/remove charge) and reset time with a
handling time per object."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from lerobot_contrast.contrast.cost import COST_MODELS, CostModel, DistanceCost, moved_objects
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.tasks.task_file.schema import CostSpec


@dataclass(frozen=True)
class HandlingTimeCost:
    """Seconds to restage: each moved object's handling time plus its travel at the operator's hand speed."""

    handling_s: Mapping[str, float] = field(default_factory=dict)
    default_handling_s: float = 3.0
    hand_speed_m_s: float = 0.25
    tolerance: float = 0.005
    name: str = "reset_time"
    unit: str = "s"

    def __call__(self, current: Scene, target: Scene) -> float:
        moves = moved_objects(current, target, self.tolerance)
        return sum(
            self.handling_s.get(name, self.default_handling_s) + distance / self.hand_speed_m_s
            for name, distance in moves.items()
        )


def make_cost_model(spec: CostSpec, name: str) -> CostModel:
    """The `--cost` model `name` with the task file's parameters."""
    if name == "distance":
        return DistanceCost(tolerance=spec.tolerance, add_remove_m=spec.add_remove)
    if name == "reset_time":
        return HandlingTimeCost(dict(spec.handling_s), spec.default_handling_s, spec.hand_speed, spec.tolerance)
    raise UserError(f"--cost: unknown cost model {name!r}; choose from: {', '.join(COST_MODELS)}")
