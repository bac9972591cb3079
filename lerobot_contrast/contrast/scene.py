"""Scenes: named objects with planar poses (metres, radians, robot frame) plus the robot's start pose."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any


@dataclass(frozen=True)
class Pose:
    """A planar pose: position (x, y) in metres and heading yaw in radians."""

    x: float
    y: float
    yaw: float = 0.0

    def distance_to(self, other: Pose) -> float:
        return math.hypot(self.x - other.x, self.y - other.y)

    def to_json(self) -> list[float]:
        return [float(self.x), float(self.y), float(self.yaw)]

    @classmethod
    def from_json(cls, data: Any) -> Pose:
        x, y, *rest = data
        return cls(float(x), float(y), float(rest[0]) if rest else 0.0)


@dataclass(frozen=True)
class Scene:
    """Object poses by name and the robot's pose (None when the task does not track it)."""

    objects: Mapping[str, Pose] = field(default_factory=dict)
    robot: Pose | None = None

    def with_object(self, name: str, pose: Pose) -> Scene:
        return replace(self, objects={**self.objects, name: pose})

    def with_robot(self, pose: Pose | None) -> Scene:
        return replace(self, robot=pose)

    def to_json(self) -> dict[str, Any]:
        return {
            "objects": {name: pose.to_json() for name, pose in self.objects.items()},
            "robot": None if self.robot is None else self.robot.to_json(),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Scene:
        robot = data.get("robot")
        return cls(
            objects={name: Pose.from_json(p) for name, p in data["objects"].items()},
            robot=None if robot is None else Pose.from_json(robot),
        )


def distance_to_segment(p: Sequence[float], a: Sequence[float], b: Sequence[float]) -> float:
    """Distance from point `p` to the segment from `a` to `b` (planar points, metres)."""
    ax, ay = b[0] - a[0], b[1] - a[1]
    length2 = ax * ax + ay * ay
    t = 0.0 if length2 == 0.0 else max(0.0, min(1.0, ((p[0] - a[0]) * ax + (p[1] - a[1]) * ay) / length2))
    return math.dist((float(p[0]), float(p[1])), (float(a[0] + t * ax), float(a[1] + t * ay)))
