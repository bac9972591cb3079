"""Cost-aware scheduling: visit the base instances (each with its chain of trials) in a cheap order.

The set of base instances stays the i.i.d. sample; only the order changes, found by nearest neighbour
plus 2-opt on the cost of staging one base scene from another.
"""

from __future__ import annotations

import numpy as np

from lerobot_contrast.contrast.cost import CostModel, DistanceCost
from lerobot_contrast.contrast.instance import Instance


def cost_matrix(bases: list[Instance], cost: CostModel) -> np.ndarray:
    """`m[i, j]`: the cost of staging base j from base i's scene.

    A chain leaves behind its base scene plus whatever the robot and the perturbations moved, which is not
    known before the run, so the base scene stands in for it.
    """
    return np.array([[cost(a.scene, b.scene) if a is not b else 0.0 for b in bases] for a in bases], dtype=np.float64)


def path_cost(m: np.ndarray, tour: np.ndarray) -> float:
    return float(m[tour[:-1], tour[1:]].sum())


def nearest_neighbour(m: np.ndarray, start: int = 0) -> np.ndarray:
    """Greedy open path from `start`: always go to the cheapest base not visited yet (ties: lowest index)."""
    n = len(m)
    visited = np.zeros(n, dtype=bool)
    tour = [start]
    visited[start] = True
    for _ in range(n - 1):
        k = int(np.argmin(np.where(visited, np.inf, m[tour[-1]])))
        tour.append(k)
        visited[k] = True
    return np.array(tour)


def two_opt(m: np.ndarray, tour: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Best-improvement 2-opt on an open path with free ends: reverse the segment that saves most, until none does.

    All n^2 reversals are scored at once from prefix sums of the forward and backward edge costs, which keeps
    this exact for asymmetric costs (a reversed segment is walked backwards).
    """
    t = tour.copy()
    n = len(t)
    if n < 3:
        return t
    i, j = np.arange(n)[:, None], np.arange(n)[None, :]
    before, after = np.maximum(i - 1, 0), np.minimum(j + 1, n - 1)
    while True:
        forward = np.concatenate([[0.0], np.cumsum(m[t[:-1], t[1:]])])
        backward = np.concatenate([[0.0], np.cumsum(m[t[1:], t[:-1]])])
        old = (forward[j] - forward[i]) + np.where(i > 0, m[t[before], t[i]], 0.0)
        old = old + np.where(j < n - 1, m[t[j], t[after]], 0.0)
        new = (backward[j] - backward[i]) + np.where(i > 0, m[t[before], t[j]], 0.0)
        new = new + np.where(j < n - 1, m[t[i], t[after]], 0.0)
        saving = np.where(j > i, old - new, 0.0)
        best = int(np.argmax(saving))
        if saving.flat[best] <= tol:
            return t
        a, b = divmod(best, n)
        t[a : b + 1] = t[a : b + 1][::-1]


def cost_aware_order(bases: list[Instance], cost: CostModel | None = None) -> np.ndarray:
    """A cheap visiting order of `bases` (indices into it): nearest neighbour from the first, then 2-opt."""
    if len(bases) < 2:
        return np.arange(len(bases))
    m = cost_matrix(bases, cost or DistanceCost())
    return two_opt(m, nearest_neighbour(m, start=0))
