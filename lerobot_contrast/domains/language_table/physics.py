"""Planar pushing physics for the Language-Table board: pymunk blocks, table friction, a kinematic effector.

Top-down 2-D model of the benchmark's PyBullet scene (metres, robot base frame, 10 Hz control).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import cache

import numpy as np
import pymunk
import pymunk.batch

from lerobot_contrast.domains.language_table.board import (
    BLOCK_FRICTION,
    BLOCK_MASS,
    CONTROL_HZ,
    EFFECTOR_FRICTION,
    EFFECTOR_RADIUS,
    MAX_ACTION,
    WORKSPACE_BOUNDS,
    block,
)
from lerobot_contrast.domains.language_table.shapes import outline

GRAVITY = 9.81
TABLE_FRICTION = 1.0  # PyBullet multiplies the two lateral frictions: block 0.5 x plane 1.0
# Fraction of the remaining distance to the target the arm covers in one control step: the benchmark's
# 0.03 m command reaches ~0.0276 m after one step and ~0.030 m after two.
TRACKING_GAIN = 0.92
MAX_SUBSTEP_TRAVEL = 0.005  # no body moves more than this per substep, so nothing tunnels through a 4 cm block
MIN_SUBSTEPS, MAX_SUBSTEPS = 2, 40
# Fraction of an overlap left uncorrected after one second (pymunk's default suits pixel-scale worlds at
# 60 Hz); this removes ~30 % per 1/60 s so a pushed block does not ride several millimetres into the effector.
COLLISION_BIAS = 0.7**60
_POSE_FIELDS = pymunk.batch.BodyFields.POSITION | pymunk.batch.BodyFields.ANGLE

BlockPoses = Mapping[str, tuple[float, float, float]]


@cache
def footprint_hull(shape: str) -> tuple[tuple[float, float], ...]:
    """Collision polygon of a block shape: the convex hull of its drawn outline, as PyBullet collides meshes."""
    hull = pymunk.Poly(None, [tuple(p) for p in outline(shape).tolist()]).get_vertices()
    return tuple((v.x, v.y) for v in hull)


def _mean_radius(hull: tuple[tuple[float, float], ...]) -> float:
    """Mean distance of the footprint's area from its centre: the lever arm of table friction on spin."""
    width = max(p[0] for p in hull) - min(p[0] for p in hull)
    height = max(p[1] for p in hull) - min(p[1] for p in hull)
    return 0.38 * (width + height) / 2  # 0.3826 x side for a square


def clip_target(x: float, y: float) -> tuple[float, float]:
    """The effector target clipped to the workspace, as the benchmark does after adding each action."""
    (x_min, y_min), (x_max, y_max) = WORKSPACE_BOUNDS
    return min(max(x, x_min), x_max), min(max(y, y_min), y_max)


class TabletopPhysics:
    """Blocks pushed by a position-controlled round effector on a table with Coulomb friction.

    `set_state` rebuilds the space, so a trajectory depends only on the state it starts from and the
    actions applied (pymunk is deterministic for identical construction and inputs).
    """

    def __init__(self, control_hz: float = CONTROL_HZ) -> None:
        self.dt = 1.0 / control_hz
        self._buffer = pymunk.batch.Buffer()
        self.set_state({}, (0.375, 0.0))

    def set_state(self, blocks: BlockPoses, effector_xy: tuple[float, float] | np.ndarray) -> None:
        """Place every block and the effector exactly (zero velocities); the effector target is its position."""
        space = pymunk.Space()
        space.collision_slop = 1e-4  # the default 0.1 assumes pixel units
        space.collision_bias = COLLISION_BIAS
        self._space = space
        self.names = tuple(blocks)
        for name, pose in blocks.items():
            self._add_block(space, name, pose)
        self._effector = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self._effector.position = (float(effector_xy[0]), float(effector_xy[1]))
        circle = pymunk.Circle(self._effector, EFFECTOR_RADIUS)
        circle.friction = EFFECTOR_FRICTION
        space.add(self._effector, circle)
        self.target = tuple(self._effector.position)
        self._poses = self._read_poses()
        self._last_travel = 0.0

    def _add_block(self, space: pymunk.Space, name: str, pose: tuple[float, float, float]) -> None:
        hull = footprint_hull(block(name).shape)
        body = pymunk.Body(BLOCK_MASS, pymunk.moment_for_poly(BLOCK_MASS, hull))
        body.position = (float(pose[0]), float(pose[1]))
        body.angle = float(pose[2])
        poly = pymunk.Poly(body, hull)
        poly.friction = BLOCK_FRICTION
        # Table friction, the usual top-down way: velocity constraints to the static body with no
        # position correction (max_bias 0) whose force is capped at the Coulomb limit.
        slide = pymunk.PivotJoint(space.static_body, body, (0.0, 0.0), (0.0, 0.0))
        spin = pymunk.GearJoint(space.static_body, body, 0.0, 1.0)
        slide_limit = BLOCK_FRICTION * TABLE_FRICTION * BLOCK_MASS * GRAVITY
        slide.max_bias, slide.max_force = 0.0, slide_limit
        spin.max_bias, spin.max_force = 0.0, slide_limit * _mean_radius(hull)
        space.add(body, poly, slide, spin)

    def _read_poses(self) -> np.ndarray:
        """(n_blocks, 3) x, y, yaw in one C call; the space lists dynamic bodies first, in insertion order."""
        self._buffer.clear()
        pymunk.batch.get_space_bodies(self._space, _POSE_FIELDS, self._buffer)
        return np.frombuffer(self._buffer.float_buf(), dtype=np.float64)[: 3 * len(self.names)].reshape(-1, 3).copy()

    def state(self) -> tuple[dict[str, tuple[float, float, float]], tuple[float, float]]:
        """Block poses by name and the effector position."""
        return dict(zip(self.names, map(tuple, self._poses.tolist()), strict=True)), self.effector

    @property
    def effector(self) -> tuple[float, float]:
        return tuple(self._effector.position)

    def step(self, action: np.ndarray | tuple[float, float]) -> None:
        """Advance one control step: move the target by the clipped delta, then track it."""
        dx = min(max(float(action[0]), -MAX_ACTION), MAX_ACTION)
        dy = min(max(float(action[1]), -MAX_ACTION), MAX_ACTION)
        self.target = clip_target(self.target[0] + dx, self.target[1] + dy)
        x0, y0 = self._effector.position
        tx, ty = TRACKING_GAIN * (self.target[0] - x0), TRACKING_GAIN * (self.target[1] - y0)
        # Pushed blocks move about as fast as the effector; last step's block travel covers coasting.
        worst = max(math.hypot(tx, ty), self._last_travel)
        substeps = min(MAX_SUBSTEPS, max(MIN_SUBSTEPS, math.ceil(worst / MAX_SUBSTEP_TRAVEL)))
        self._effector.velocity = (tx / self.dt, ty / self.dt)
        h = self.dt / substeps
        for _ in range(substeps):
            self._space.step(h)
        # Land exactly on the tracked point: kinematic integration accumulates rounding over substeps.
        self._effector.position = (x0 + tx, y0 + ty)
        self._effector.velocity = (0.0, 0.0)
        poses = self._read_poses()
        moved = poses[:, :2] - self._poses[:, :2]
        self._last_travel = float(np.sqrt((moved * moved).sum(axis=1).max(initial=0.0)))
        self._poses = poses
