"""Cost models: the experimenter effort to turn the scene the robot left behind into the next one.

Only objects count; resetting the robot itself is free, as in the paper (it is the same for every
strategy and can be automated). Language perturbations leave the scene alone and so cost nothing.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Scene


class CostModel(Protocol):
    name: str
    unit: str

    def __call__(self, current: Scene, target: Scene) -> float: ...


def moved_objects(current: Scene, target: Scene, tolerance: float) -> dict[str, float]:
    """Planar distance each object must travel, for objects displaced by more than `tolerance`.

    Objects only in `target` must be brought in and objects only in `current` taken away; both are
    reported with distance 0.0 so the caller can price the handling itself.
    """
    moves: dict[str, float] = {}
    for name, pose in target.objects.items():
        before = current.objects.get(name)
        if before is None:
            moves[name] = 0.0
            continue
        distance = before.distance_to(pose)
        if distance > tolerance:
            moves[name] = distance
    for name in current.objects.keys() - target.objects.keys():
        moves[name] = 0.0
    return moves


@dataclass(frozen=True)
class DistanceCost:
    """Metres objects are moved (the paper's simulation cost).

    `tolerance` ignores displacements an operator would not correct (placement precision);
    `add_remove_m` prices bringing an object in from, or taking it out to, the side of the workspace.
    """

    tolerance: float = 0.005
    add_remove_m: float = 0.0
    name: str = "distance"
    unit: str = "m"

    def __call__(self, current: Scene, target: Scene) -> float:
        moves = moved_objects(current, target, self.tolerance)
        return sum(d if d > 0.0 else self.add_remove_m for d in moves.values())


@dataclass(frozen=True)
class ResetTimeCost:
    """Seconds an operator needs to restage the scene: a fixed handling time per moved object plus travel.

    In simulation this is a model; on hardware the measured reset time replaces it.
    """

    per_object_s: float = 3.0
    hand_speed_m_s: float = 0.25
    tolerance: float = 0.005
    # Handling times of particular objects (seconds), where they differ from `per_object_s`.
    handling_s: Mapping[str, float] = field(default_factory=dict)
    name: str = "reset_time"
    unit: str = "s"

    def __call__(self, current: Scene, target: Scene) -> float:
        moves = moved_objects(current, target, self.tolerance)
        return sum(self.handling_s.get(n, self.per_object_s) + d / self.hand_speed_m_s for n, d in moves.items())


@dataclass(frozen=True)
class RobotTimeCost:
    """Seconds the robot spends staging the scene itself (`--operator=arm`): one pick-and-place per moved object,
    whose planned motions take `per_object_s` whatever the distance. The seconds it measures replace the plan."""

    per_object_s: float = 0.0
    tolerance: float = 0.005
    name: str = "robot_time"
    unit: str = "s"

    def __call__(self, current: Scene, target: Scene) -> float:
        return self.per_object_s * len(moved_objects(current, target, self.tolerance))


@dataclass(frozen=True)
class InterventionCost:
    """Times a person is called to the bench (`--operator=arm`): planned as none, counted as they happen."""

    name: str = "interventions"
    unit: str = "calls"

    def __call__(self, current: Scene, target: Scene) -> float:
        return 0.0


# measured: planned as distance; a calibrated camera's measurement of each staging replaces it (staging/check.py).
COST_MODELS = {
    "distance": DistanceCost,
    "reset_time": ResetTimeCost,
    "measured": partial(DistanceCost, name="measured"),
    "robot_time": RobotTimeCost,
    "interventions": InterventionCost,
}


def make_cost_model(name: str) -> CostModel:
    try:
        return COST_MODELS[name]()
    except KeyError:
        raise UserError(f"--cost: unknown cost model {name!r}; choose from: {', '.join(COST_MODELS)}") from None
