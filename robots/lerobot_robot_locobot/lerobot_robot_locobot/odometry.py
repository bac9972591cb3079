"""Planar poses as (x, y, theta) tuples: composition, inversion and an adjustable odometry frame."""

from __future__ import annotations

import math

Pose2 = tuple[float, float, float]


def wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def compose(a: Pose2, b: Pose2) -> Pose2:
    """a ⊕ b: pose b expressed in frame a, returned in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2]))


def inverse(a: Pose2) -> Pose2:
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], wrap(-a[2]))


class OdometryFrame:
    """Maps the base's raw odometry into the frame the client asked for: after `set(pose)` the current raw
    odometry reads as `pose` (e.g. the robot's start pose in the apartment), and motion continues from there."""

    def __init__(self) -> None:
        self.offset: Pose2 = (0.0, 0.0, 0.0)

    def set(self, raw: Pose2, pose: Pose2) -> None:
        self.offset = compose(pose, inverse(raw))

    def reset(self) -> None:
        self.offset = (0.0, 0.0, 0.0)

    def apply(self, raw: Pose2) -> Pose2:
        return compose(self.offset, raw)
