"""The navigator's episode memory: where each furniture category was seen, in the odometry frame."""

from __future__ import annotations

import math

import torch
from torch import Tensor


class SightMemory:
    """Per category, the last `capacity` surface points the scanner attributed to it (odometry frame, metres)."""

    def __init__(self, categories: int, capacity: int, recent: int = 60, quantile: float = 0.25, min_points: int = 3):
        self.capacity, self.recent, self.quantile, self.min_points = capacity, recent, quantile, min_points
        self.points: list[Tensor] = [torch.zeros(0, 2) for _ in range(categories)]

    def add(self, pose: Tensor, bearings: Tensor, ranges: Tensor, classes: Tensor, keep: Tensor) -> None:
        """Columns with `keep` set saw category `classes` at `ranges` along `bearings` from `pose` (x, y, yaw)."""
        angles = pose[2] + bearings
        xy = torch.stack([pose[0] + ranges * torch.cos(angles), pose[1] + ranges * torch.sin(angles)], -1)
        for k in torch.unique(classes[keep]).tolist():
            seen = xy[keep & (classes == k)]
            self.points[k] = torch.cat([self.points[k], seen])[-self.capacity :]

    def nearest(self, category: int, pose: Tensor) -> tuple[float, float] | None:
        """A near remembered point of `category` in the robot frame (x ahead, y left), or None if unseen: the one at
        the `quantile` of the recent points' distances, so a few misread ranges or stray columns do not decide."""
        points = self.points[category][-self.recent :]
        if len(points) < self.min_points:
            return None
        delta = points - pose[:2]
        distance = delta.norm(dim=-1)
        i = int(distance.argsort()[int(self.quantile * (len(distance) - 1))])
        c, s = math.cos(float(pose[2])), math.sin(float(pose[2]))
        dx, dy = float(delta[i, 0]), float(delta[i, 1])
        return c * dx + s * dy, -s * dx + c * dy
