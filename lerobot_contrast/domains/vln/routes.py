"""Reference routes for VLN instances on the apartment's occupancy grid, route comparisons for the
perturbations' claims, and path metrics (nDTW)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import lru_cache

import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln.apartment import Footprints, Grid, Room, Route, clearance, hausdorff, resample

ROOM = Room()
ROBOT_RADIUS = 0.18
GRID_RESOLUTION = 0.1
# Two routes are "the same" when no point of one is farther than this from the other (and their lengths
# agree to within SAME_LENGTH_M); "different" when some point is at least DIFFERENT_ROUTE_M away.
SAME_ROUTE_M = 0.15
SAME_LENGTH_M = 0.1
DIFFERENT_ROUTE_M = 0.4
# VLN-CE samples reference paths about once per forward step.
REFERENCE_SPACING_M = 0.25

ObjectsKey = tuple[tuple[str, float, float, float], ...]


def objects_key(objects: Mapping[str, Pose]) -> ObjectsKey:
    return tuple(sorted((name, round(p.x, 4), round(p.y, 4), round(p.yaw, 4)) for name, p in objects.items()))


@lru_cache(maxsize=64)
def grid_for(key: ObjectsKey, robot_radius: float = ROBOT_RADIUS) -> Grid:
    objects = {name: Pose(x, y, yaw) for name, x, y, yaw in key}
    return Grid(ROOM, Footprints.from_objects(objects), robot_radius, GRID_RESOLUTION)


@lru_cache(maxsize=512)
def _route(
    key: ObjectsKey, start: tuple[float, float], subgoals: tuple[str, ...], radius: float, robot_radius: float
) -> Route | None:
    grid = grid_for(key, robot_radius)
    return grid.route(Pose(*start), [grid.region(name, radius) for name in subgoals])


def plan(
    scene: Scene, start: Pose, subgoals: Sequence[str], radius: float, robot_radius: float = ROBOT_RADIUS
) -> Route | None:
    """The shortest route from `start` that comes within `radius` of each subgoal object, in order, for a
    robot of `robot_radius` (a larger one keeps the route away from furniture)."""
    if any(name not in scene.objects for name in subgoals):
        return None
    key = objects_key(scene.objects)
    return _route(key, (round(start.x, 4), round(start.y, 4)), tuple(subgoals), radius, robot_radius)


def start_is_free(scene: Scene, start: Pose) -> bool:
    """Whether the robot's disc fits at `start` without touching a wall or furniture."""
    footprints = grid_for(objects_key(scene.objects)).footprints
    return bool(clearance(ROOM, footprints, np.array([start.x, start.y]))[0] >= ROBOT_RADIUS)


def same_route(a: Route, b: Route) -> bool:
    return hausdorff(a.points, b.points) <= SAME_ROUTE_M and abs(a.length - b.length) <= SAME_LENGTH_M


def different_route(a: Route, b: Route) -> bool:
    return hausdorff(a.points, b.points) >= DIFFERENT_ROUTE_M


def distance_to_object(scene: Scene, name: str, points: np.ndarray) -> np.ndarray:
    """Distance from each point (P, 2) to the outline of furniture `name` (negative inside it)."""
    footprints = Footprints.from_objects({name: scene.objects[name]})
    return footprints.signed_distance(points)[:, 0]


def dtw(query: np.ndarray, reference: np.ndarray) -> float:
    """Dynamic time warping distance between two point sequences, Euclidean point cost (exact)."""
    cost = np.linalg.norm(query[:, None, :] - reference[None, :, :], axis=-1)
    acc = np.full((len(query) + 1, len(reference) + 1), np.inf)
    acc[0, 0] = 0.0
    for i in range(1, len(query) + 1):
        row, prev = acc[i], acc[i - 1]
        for j in range(1, len(reference) + 1):
            row[j] = cost[i - 1, j - 1] + min(prev[j], row[j - 1], prev[j - 1])
    return float(acc[-1, -1])


def ndtw(path: np.ndarray, reference: np.ndarray, threshold: float) -> float:
    """Normalised DTW (Ilharco et al. 2019, as VLN-CE computes it): exp(-DTW(Q, R) / (|R| * threshold)), with
    Q the agent's positions (consecutive duplicates dropped) and R the reference resampled every 0.25 m."""
    query = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(query, axis=0), axis=1) > 1e-9])
    ref = resample(reference, REFERENCE_SPACING_M)
    return math.exp(-dtw(query[keep], ref) / (len(ref) * threshold))
