"""The navigator's episode memory: where each furniture category was seen, in the odometry frame."""

from __future__ import annotations

import numpy as np


class SightMemory:
    """Per category, the last `capacity` surface points the scanner attributed to it (odometry frame, metres), and
    how far away each was seen from."""

    def __init__(self, categories: int, capacity: int) -> None:
        self.capacity = capacity
        self.seen: list[np.ndarray] = [np.zeros((0, 3)) for _ in range(categories)]

    def points(self, category: int, within_m: float = np.inf) -> np.ndarray:
        """(P, 2) points of `category` seen from at most `within_m` away."""
        seen = self.seen[category]
        return seen[seen[:, 2] <= within_m, :2]

    def add(self, pose: np.ndarray, bearings: np.ndarray, ranges: np.ndarray, classes: np.ndarray, keep: np.ndarray):
        """Columns with `keep` set saw category `classes` at `ranges` along `bearings` from `pose` (x, y, yaw)."""
        angles = pose[2] + bearings
        xyr = np.stack([pose[0] + ranges * np.cos(angles), pose[1] + ranges * np.sin(angles), ranges], -1)
        for k in np.unique(classes[keep]).tolist():
            seen = xyr[keep & (classes == k)]
            self.seen[k] = np.concatenate([self.seen[k], seen])[-self.capacity :]
