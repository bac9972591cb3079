"""The shortest-path teacher of the `vln_navigator` policy and the privileged targets of one navigation frame.

The teacher is stateless, so it can relabel any state a learner visits (DAgger): from the geodesic cost-to-go of
the remaining subgoals on the planner's grid, it turns towards the one of the twelve reachable headings whose
look-ahead point is cheapest, drives forward when that heading is the current one, and stops at the final subgoal.
"""

from __future__ import annotations

import math

import numpy as np
from lerobot_policy_vln_navigator.configuration_vln_navigator import CATEGORIES, COMMANDS
from lerobot_policy_vln_navigator.network import column_bearings

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln import routes
from lerobot_contrast.domains.vln.apartment import Footprints, Grid, furniture_for

# The teacher aims this far inside the success radius, and counts a subgoal reached (or stops) this far inside.
AIM_MARGIN_M = 0.3
REACHED_MARGIN_M = 0.15
# It keeps this much more than the robot's radius from furniture where it can (30 degree turns and 0.25 m steps
# do not thread narrow gaps), and looks this far ahead along each heading.
CLEARANCE_M = 0.1
LOOKAHEAD_M = (0.15, 0.3, 0.45)
TURN = math.radians(30.0)
SCAN_COLUMNS = 32
HFOV_DEG = 69.0
WALL = len(CATEGORIES)


def category_index(name: str) -> int:
    return CATEGORIES.index(furniture_for(name).category)


class Teacher:
    """Relabels any pose of one instance with the command the shortest route asks for."""

    def __init__(self, instance: Instance) -> None:
        self.instance = instance
        self.subgoals = list(instance.goal["subgoals"])
        self.radius = float(instance.goal["radius"])
        scene = instance.scene
        self.footprints = Footprints.from_objects(scene.objects)
        for clearance in (CLEARANCE_M, 0.0):
            grid = Grid(routes.ROOM, self.footprints, routes.ROBOT_RADIUS + clearance, routes.GRID_RESOLUTION)
            fields = self._fields(grid)
            if fields is not None:
                break
        self.grid, self.fields = grid, fields

    def _fields(self, grid: Grid) -> list[np.ndarray] | None:
        """Cost-to-go (metres) to finish from every cell: [while the first subgoal is ahead, after it]."""
        aim = max(0.1, self.radius - AIM_MARGIN_M)
        final = grid.region(self.subgoals[1], aim)
        first = grid.region(self.subgoals[0], aim)
        if not final.any() or not first.any():
            return None
        after = grid.geodesic(np.where(final, 0.0, np.inf))
        before = grid.geodesic(np.where(first, after, np.inf))
        return [before, after] if np.isfinite(before).any() else None

    def distance(self, phase: int, x: float, y: float) -> float:
        """Distance from (x, y) to the outline of subgoal `phase` (0: first, 1: final)."""
        name = self.subgoals[phase]
        return float(routes.distance_to_object(self.instance.scene, name, np.array([[x, y]]))[0])

    def phase(self, phase: int, pose: Pose) -> int:
        """The subgoal ahead after reaching `pose`: 1 once the first one has been reached."""
        return 1 if phase == 1 or self.distance(0, pose.x, pose.y) <= self.radius - REACHED_MARGIN_M else 0

    def act(self, pose: Pose, phase: int) -> str:
        if phase == 1 and self.distance(1, pose.x, pose.y) <= self.radius - REACHED_MARGIN_M:
            return "stop"
        if self.fields is None:
            return "stop"
        field = self.fields[phase]
        costs = [self._cost(field, pose, pose.yaw + k * TURN) for k in range(12)]
        best = int(np.argmin(costs))
        if not np.isfinite(costs[best]):
            return "turn_left"
        if best == 0 or costs[0] <= costs[best] + 1e-6:
            return "forward"
        return "turn_left" if best <= 6 else "turn_right"

    def _cost(self, field: np.ndarray, pose: Pose, heading: float) -> float:
        """Cost-to-go at the look-ahead point along `heading`; inf if the way there is blocked."""
        for step in LOOKAHEAD_M:
            x, y = pose.x + step * math.cos(heading), pose.y + step * math.sin(heading)
            col, row = int(x / self.grid.resolution), int(y / self.grid.resolution)
            if not (0 <= row < self.grid.shape[0] and 0 <= col < self.grid.shape[1]) or not self.grid.free[row, col]:
                return math.inf
        return float(field[row, col])

    def targets(self, pose: Pose) -> dict[str, np.ndarray]:
        """The privileged targets of a frame at `pose` (see `features`)."""
        origin = np.array([pose.x, pose.y])
        angles = pose.yaw + column_bearings(SCAN_COLUMNS, HFOV_DEG).numpy().astype(np.float64)
        dirs = np.stack([np.cos(angles), np.sin(angles)], -1)
        wall_t, _ = routes.ROOM.exit(origin, dirs)
        t_in, _, _ = self.footprints.ray_hits(origin, dirs)
        t_in = np.where(t_in >= 0, t_in, np.inf)
        nearest = t_in.argmin(axis=1)
        hit = t_in[np.arange(len(dirs)), nearest]
        classes = np.array([category_index(self.footprints.names[i]) for i in nearest])
        column_class = np.where(hit < wall_t, classes, WALL)
        first, final = np.zeros(WALL, np.float32), np.zeros(WALL, np.float32)
        first[category_index(self.subgoals[0])] = 1.0
        final[category_index(self.subgoals[1])] = 1.0
        return {
            "column_class": column_class.astype(np.float32),
            "column_range": np.minimum(hit, wall_t).astype(np.float32),
            "first": first,
            "final": final,
        }


SHAPES = {"column_class": (SCAN_COLUMNS,), "column_range": (SCAN_COLUMNS,), "first": (WALL,), "final": (WALL,)}


def one_hot(command: str) -> np.ndarray:
    return np.array([float(c == command) for c in COMMANDS], np.float32)
