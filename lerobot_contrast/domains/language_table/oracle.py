"""A scripted block pusher for Language-Table instances, and the reference path length it gives SPL.

Reference path (`reference_path`): the effector path length (sum of |delta effector_translation| per step) of
the noise-free `PushOracle` run in a fresh state-only physics from `instance.scene` until success or max_steps.
The benchmark's own RRT* oracle is not a shortest-path planner either, so no executable reference is optimal;
we take ours because it runs in the same simulator, so the oracle itself scores SPL 1 on every success. Where it
fails we fall back to the straight-line estimate |effector -> pre-push point| + |block -> goal point| and flag it
with success=False; it ignores the success radius and obstacles, so it is an estimate, not a bound.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table.board import MAX_ACTION, MAX_EPISODE_STEPS, WORKSPACE_BOUNDS
from lerobot_contrast.domains.language_table.physics import TabletopPhysics

PRE_PUSH_BACKOFFS = (0.05, 0.06, 0.07, 0.08)  # effector starts a push this far behind the block (benchmark's)
# Centre distances kept while travelling, loosest first: effector to blocks (radii 0.028 + 0.0127 + margin)
# and pushed block to other blocks (two radii + margin; the tighter value lets a block brush past).
EFFECTOR_CLEARANCES = (0.047, 0.04)
BLOCK_CLEARANCES = (0.06, 0.05)
DETOUR_INSET = 0.02  # detours keep this far inside the workspace, so the effector can still follow
ALIGN_ENTER, ALIGN_LEAVE = 0.006, 0.01  # lateral offset of the effector from the push line (hysteresis)
PUSH_REACH = PRE_PUSH_BACKOFFS[-1] + 0.01  # pushing goes on while the block is at most this far ahead
AIM_BEHIND = 0.01  # the pusher aims this far behind the block centre, i.e. into the block
LOOKAHEAD = 0.03  # the block is pushed towards the point this far along its planned path
GOAL_TOLERANCE = 0.005
PUSH_SPEED, APPROACH_SPEED = 0.035, 0.03  # metres per 10 Hz step (0.35 and 0.3 m/s)
SLOWDOWN = ((0.02, 0.2), (0.04, 0.3), (0.06, 0.4), (0.08, 0.5), (0.1, 0.6))  # (block-goal distance, speed factor)
# Push directions tried when the effector cannot stand behind the block: 15° turns up to ±90°, nearest first.
PUSH_TURNS = tuple(sign * k * math.pi / 12 for k in range(7) for sign in (1, -1))[1:]
RING_VERTICES = 8
RING_SCALE = 1.0 / math.cos(math.pi / RING_VERTICES) + 0.01  # polygon edges then stay outside the circle


def _unit(v: np.ndarray) -> np.ndarray:
    n = math.hypot(v[0], v[1])
    return v / n if n > 1e-12 else np.array((1.0, 0.0))


def _limit(v: np.ndarray, speed: float) -> np.ndarray:
    n = math.hypot(v[0], v[1])
    return v * (speed / n) if n > speed else v


def _inside_workspace(points: np.ndarray, inset: float) -> np.ndarray:
    (x_min, y_min), (x_max, y_max) = WORKSPACE_BOUNDS
    x, y = points[:, 0], points[:, 1]
    return (x >= x_min + inset) & (x <= x_max - inset) & (y >= y_min + inset) & (y <= y_max - inset)


def _segments_clear(a: np.ndarray, b: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """For segment endpoints a, b (..., 2): whether each segment keeps outside every obstacle circle."""
    # x and y kept apart: numpy reductions over a length-2 axis cost more than the arithmetic.
    dx, dy = b[..., :1] - a[..., :1], b[..., 1:] - a[..., 1:]
    cx, cy = centres[:, 0] - a[..., :1], centres[:, 1] - a[..., 1:]
    t = np.clip((cx * dx + cy * dy) / np.maximum(dx * dx + dy * dy, 1e-18), 0.0, 1.0)
    gx, gy = cx - t * dx, cy - t * dy
    return (gx * gx + gy * gy >= (radii * (1 - 1e-6)) ** 2).all(-1)


def _dijkstra(weights: np.ndarray, source: int, target: int) -> list[int] | None:
    n = len(weights)
    dist, prev, done = np.full(n, np.inf), np.full(n, -1), np.zeros(n, bool)
    dist[source] = 0.0
    for _ in range(n):
        i = int(np.argmin(np.where(done, np.inf, dist)))
        if done[i] or not np.isfinite(dist[i]) or i == target:
            break
        done[i] = True
        alt = dist[i] + weights[i]
        better = alt < dist
        dist[better], prev[better] = alt[better], i
    if not np.isfinite(dist[target]):
        return None
    order = [target]
    while order[-1] != source:
        order.append(int(prev[order[-1]]))
    return order[::-1]


def plan_path(start: np.ndarray, goal: np.ndarray, centres: np.ndarray, radius: float) -> np.ndarray | None:
    """Shortest polyline (K, 2) from start to goal around obstacle circles, via their circumscribed polygons.

    Circles that hold the start (or goal) only forbid getting closer to their centre on the first (last) leg,
    so a path can leave a crowd and end next to a block. Detours stay DETOUR_INSET inside the workspace.
    None when no such path exists.
    """
    radii = np.full(len(centres), radius)
    from_start = np.minimum(radii, np.linalg.norm(centres - start, axis=1))
    to_goal = np.minimum(radii, np.linalg.norm(centres - goal, axis=1))
    if len(centres) == 0 or _segments_clear(start, goal, centres, np.minimum(from_start, to_goal)):
        return np.array((start, goal))
    angles = 2 * np.pi * np.arange(RING_VERTICES) / RING_VERTICES
    ring = np.stack((np.cos(angles), np.sin(angles)), axis=1)
    vertices = (centres[:, None, :] + radius * RING_SCALE * ring).reshape(-1, 2)
    outside = (np.linalg.norm(vertices[:, None, :] - centres, axis=2) >= radius).all(axis=1)
    nodes = np.concatenate(([start, goal], vertices[outside & _inside_workspace(vertices, DETOUR_INSET)]))
    i, j = np.triu_indices(len(nodes), 1)
    visible = np.zeros((len(nodes), len(nodes)), bool)
    visible[i, j] = visible[j, i] = _segments_clear(nodes[i], nodes[j], centres, radii)
    visible[0] = _segments_clear(start, nodes, centres, from_start)
    visible[:, 1] = _segments_clear(nodes, goal, centres, to_goal)
    weights = np.where(visible, np.linalg.norm(nodes[:, None, :] - nodes[None, :, :], axis=2), np.inf)
    order = _dijkstra(weights, 0, 1)
    return None if order is None else nodes[order]


def route(start: np.ndarray, goal: np.ndarray, centres: np.ndarray, clearances: tuple[float, ...]) -> np.ndarray:
    """The path of the first clearance that admits one (tighter ones squeeze through gaps), else the straight line."""
    for clearance in clearances:
        path = plan_path(start, goal, centres, clearance)
        if path is not None:
            return path
    return np.array((start, goal))


def along(path: np.ndarray, distance: float) -> np.ndarray:
    """The point `distance` along the polyline (its end when the polyline is shorter)."""
    for a, b in zip(path[:-1], path[1:], strict=True):
        step = math.dist(a, b)
        if distance <= step:
            return a + (b - a) * (distance / max(step, 1e-12))
        distance -= step
    return path[-1]


def reachable(goal: np.ndarray) -> np.ndarray:
    """Where the oracle pushes towards `goal`: goals off the reachable board (absolute corners) move in, so the
    effector still fits behind the block."""
    (x_min, y_min), (x_max, y_max) = WORKSPACE_BOUNDS
    inset = PRE_PUSH_BACKOFFS[0]
    return np.clip(goal, (x_min + inset, y_min + inset), (x_max - inset, y_max - inset))


def _blocks_xy(scene: Scene) -> dict[str, np.ndarray]:
    return {name: np.array((p.x, p.y)) for name, p in scene.objects.items()}


def _as_scene(scene_or_state: Scene | Mapping[str, tuple[float, float, float]]) -> Scene:
    if isinstance(scene_or_state, Scene):
        return scene_or_state
    return Scene(objects={name: Pose(*pose) for name, pose in scene_or_state.items()})


class PushOracle:
    """Pushes the task's current push block towards its goal: go behind it, then push through its centre.

    `task` provides `push_target(instance, scene)` and `is_achieved(instance, scene)`.
    """

    def __init__(self, task, noise_std: float = 0.0, rng: np.random.Generator | None = None) -> None:
        self.task = task
        self.noise_std = noise_std
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.instance: Instance | None = None
        self._pushing = False

    def reset(self, instance: Instance) -> None:
        self.instance = instance
        self._pushing = False

    def act(self, scene_or_state, effector_target_xy) -> np.ndarray:
        """Action (2,) float32: the next effector-target delta, given block poses and the current target."""
        scene = _as_scene(scene_or_state)
        action = np.zeros(2) if self.task.is_achieved(self.instance, scene) else self._plan(scene, effector_target_xy)
        if self.noise_std > 0:
            action = action + self.rng.normal(0.0, self.noise_std, 2)
        return np.clip(action, -MAX_ACTION, MAX_ACTION).astype(np.float32)

    def _plan(self, scene: Scene, effector_target_xy) -> np.ndarray:
        name, goal = self.task.push_target(self.instance, scene)
        goal = reachable(goal)
        blocks = _blocks_xy(scene)
        block = blocks.pop(name)
        if math.dist(block, goal) < GOAL_TOLERANCE:
            return np.zeros(2)
        others = list(blocks.values())
        block_path = route(block, goal, np.array(others).reshape(-1, 2), BLOCK_CLEARANCES)
        direction, pre_push = _push_setup(block, _unit(along(block_path, LOOKAHEAD) - block), others)
        effector = np.asarray(effector_target_xy, dtype=float)
        rel = block - effector
        along_push, lateral = float(rel @ direction), abs(float(rel[0] * direction[1] - rel[1] * direction[0]))
        aligned = lateral < (ALIGN_LEAVE if self._pushing else ALIGN_ENTER)
        self._pushing = aligned and 0.0 < along_push < PUSH_REACH
        if self._pushing:
            aim = block - AIM_BEHIND * direction
            return _limit(aim - effector, PUSH_SPEED * _slowdown(math.dist(block, goal)))
        path = route(effector, pre_push, np.array([*others, block]), EFFECTOR_CLEARANCES)
        return along(path, APPROACH_SPEED) - effector


def _push_setup(block: np.ndarray, direction: np.ndarray, others: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Push direction and pre-push point: the direction turned as little as needed (blocks at the board edge,
    blocks crowded behind) for the effector to stand behind the block, on the board and clear of the others."""
    for angle in PUSH_TURNS:
        c, s = math.cos(angle), math.sin(angle)
        turned = np.array((c * direction[0] - s * direction[1], s * direction[0] + c * direction[1]))
        for backoff in PRE_PUSH_BACKOFFS:
            point = block - backoff * turned
            clear = all(math.dist(point, xy) > EFFECTOR_CLEARANCES[0] for xy in others)
            if clear and _inside_workspace(point[None], 0.0)[0]:
                return turned, point
    return direction, block - PRE_PUSH_BACKOFFS[0] * direction


def _slowdown(distance: float) -> float:
    return next((factor for limit, factor in SLOWDOWN if distance < limit), 1.0)


@dataclass(frozen=True)
class ReferencePath:
    """Reference effector path for SPL: its length (m), the steps it took, and whether the oracle succeeded."""

    length_m: float
    steps: int
    success: bool


def reference_path(task, instance: Instance, max_steps: int = MAX_EPISODE_STEPS) -> ReferencePath:
    """The noise-free oracle's executed effector path from `instance.scene` (see the module docstring)."""
    physics = TabletopPhysics()
    robot = instance.scene.robot or Pose(*physics.effector)
    physics.set_state({n: (p.x, p.y, p.yaw) for n, p in instance.scene.objects.items()}, (robot.x, robot.y))
    oracle = PushOracle(task)
    oracle.reset(instance)
    length, effector = 0.0, physics.effector
    for step in range(max_steps + 1):
        scene = _as_scene(physics.state()[0])
        if task.is_achieved(instance, scene):
            return ReferencePath(length, step, True)
        if step == max_steps:
            break
        physics.step(oracle.act(scene, physics.target))
        length += math.dist(physics.effector, effector)
        effector = physics.effector
    return ReferencePath(_straight_line_estimate(task, instance), max_steps, False)


def _straight_line_estimate(task, instance: Instance) -> float:
    """|effector -> pre-push point| + |block -> goal| in the instance's start scene."""
    name, goal = task.push_target(instance, instance.scene)
    block = _blocks_xy(instance.scene)[name]
    pre_push = block - PRE_PUSH_BACKOFFS[0] * _unit(np.asarray(goal, dtype=float) - block)
    robot = instance.scene.robot
    start = np.array((robot.x, robot.y)) if robot is not None else pre_push
    return math.dist(start, pre_push) + math.dist(block, goal)
