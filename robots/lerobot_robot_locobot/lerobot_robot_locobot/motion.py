"""Closed-loop discrete motions on odometry: drive a distance or turn an angle, slowing near the target.

Unlike Interbotix's `move(x, yaw, duration)` (velocity x time, open loop), each motion ends when odometry
says the distance or angle is reached, so a 0.25 m step is 0.25 m whatever the floor or the battery."""

from __future__ import annotations

import math
from dataclasses import dataclass

from lerobot_robot_locobot.odometry import Pose2, wrap


@dataclass(frozen=True)
class MotionLimits:
    x_vel: float = 0.2  # m/s, cruising speed of a forward step
    theta_vel: float = 0.6  # rad/s, of a turn
    min_x_vel: float = 0.03  # below this the base stalls instead of creeping to the target
    min_theta_vel: float = 0.15
    gain: float = 1.5  # 1/s: speed = gain x remaining, between the minimum and the cruising speed
    tolerance_m: float = 0.01
    tolerance_rad: float = math.radians(1.5)
    timeout_s: float = 10.0


class Motion:
    """One forward step (`kind` "forward", `target` metres, negative backwards) or turn ("turn", radians, positive
    to the left) from `start`. Call `update` with each new odometry pose until it returns a result."""

    def __init__(self, kind: str, target: float, start: Pose2, now: float, limits: MotionLimits) -> None:
        if kind not in ("forward", "turn"):
            raise ValueError(f"motion kind must be forward or turn, got {kind!r}")
        self.kind, self.target, self.start, self.started, self.limits = kind, target, start, now, limits
        self._turned, self._last_theta = 0.0, start[2]

    def progress(self, pose: Pose2) -> float:
        """Metres driven along the start heading, or radians turned (summed, so turns beyond 180 degrees count)."""
        if self.kind == "forward":
            dx, dy = pose[0] - self.start[0], pose[1] - self.start[1]
            return dx * math.cos(self.start[2]) + dy * math.sin(self.start[2])
        self._turned += wrap(pose[2] - self._last_theta)
        self._last_theta = pose[2]
        return self._turned

    def update(self, pose: Pose2, now: float, bumper: bool) -> tuple[float, float] | str:
        """The (x, theta) velocity to command now, or the result: "done", "blocked" (the bumper stopped a forward
        step) or "timeout"."""
        remaining = self.target - self.progress(pose)
        forward = self.kind == "forward"
        if abs(remaining) <= (self.limits.tolerance_m if forward else self.limits.tolerance_rad):
            return "done"
        if forward and bumper:
            return "blocked"
        if now - self.started > self.limits.timeout_s:
            return "timeout"
        top, bottom = (
            (self.limits.x_vel, self.limits.min_x_vel)
            if forward
            else (self.limits.theta_vel, self.limits.min_theta_vel)
        )
        speed = math.copysign(min(top, max(bottom, self.limits.gain * abs(remaining))), remaining)
        return (speed, 0.0) if forward else (0.0, speed)
