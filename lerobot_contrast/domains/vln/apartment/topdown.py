"""A top-down map of the apartment: furniture footprints with names, the robot, a path and goal regions."""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment.geometry import Footprints, Room

FLOOR = (236, 226, 208)
WALL = (60, 60, 60)
ROBOT = (20, 20, 20)
PATH = (220, 40, 40)
REFERENCE = (40, 120, 220)
GOAL = (40, 170, 90)


def render_map(
    room: Room,
    footprints: Footprints,
    robot: Pose | None = None,
    robot_radius: float = 0.18,
    path: Sequence[tuple[float, float]] = (),
    reference: Sequence[tuple[float, float]] = (),
    goals: Sequence[tuple[str, float]] = (),
    px_per_m: float = 60.0,
) -> np.ndarray:
    """RGB (H, W, 3) uint8 map, +y up. `goals` are (furniture name, radius) drawn as outlines at that
    distance around the footprint; `path` (red) and `reference` (blue) are polylines of (x, y)."""
    margin = 10
    width, height = int(room.size_x * px_per_m) + 2 * margin, int(room.size_y * px_per_m) + 2 * margin

    def px(points: np.ndarray) -> np.ndarray:
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        return np.stack([margin + points[:, 0] * px_per_m, height - margin - points[:, 1] * px_per_m], -1).round()

    image = np.full((height, width, 3), 255, dtype=np.uint8)
    corners = px(np.array([[0, 0], [room.size_x, 0], [room.size_x, room.size_y], [0, room.size_y]]))
    cv2.fillPoly(image, [corners.astype(np.int32)], FLOOR)
    cv2.polylines(image, [corners.astype(np.int32)], True, WALL, 3)
    for name, radius in goals:
        _goal_outline(image, footprints, footprints.index(name), radius, px)
    for i, name in enumerate(footprints.names):
        color = tuple(int(c) for c in footprints.colors[i])
        if footprints.is_box[i]:
            cv2.fillPoly(image, [px(footprints.corners(i)).astype(np.int32)], color, cv2.LINE_AA)
        else:
            center = px(footprints.centers[i])[0].astype(np.int32)
            cv2.circle(image, tuple(center), int(footprints.half[i, 0] * px_per_m), color, -1, cv2.LINE_AA)
        label = px(footprints.centers[i])[0].astype(np.int32) + [-4 * len(name), 4]
        cv2.putText(image, name, tuple(int(v) for v in label), cv2.FONT_HERSHEY_SIMPLEX, 0.4, WALL, 1, cv2.LINE_AA)
    for line, color in ((reference, REFERENCE), (path, PATH)):
        if len(line) > 1:
            cv2.polylines(image, [px(np.asarray(line)).astype(np.int32)], False, color, 2, cv2.LINE_AA)
    if robot is not None:
        center = px(np.array([robot.x, robot.y]))[0]
        tip = px(np.array([robot.x + robot_radius * math.cos(robot.yaw), robot.y + robot_radius * math.sin(robot.yaw)]))
        cv2.circle(image, tuple(center.astype(np.int32)), int(robot_radius * px_per_m), ROBOT, 2, cv2.LINE_AA)
        cv2.line(image, tuple(center.astype(np.int32)), tuple(tip[0].astype(np.int32)), ROBOT, 2, cv2.LINE_AA)
    return image


def _goal_outline(image: np.ndarray, footprints: Footprints, i: int, radius: float, px) -> None:
    """The set of points within `radius` of footprint `i`, outlined."""
    angles = np.linspace(0, 2 * math.pi, 72, endpoint=False)
    if footprints.is_box[i]:
        # A rounded rectangle: each corner swept by a quarter circle of `radius`.
        corners = footprints.corners(i)
        ring = (corners[:, None, :] + radius * np.stack([np.cos(angles), np.sin(angles)], -1)[None]).reshape(-1, 2)
        hull = cv2.convexHull(px(ring).astype(np.float32)).reshape(-1, 2)
    else:
        r = footprints.half[i, 0] + radius
        hull = px(footprints.centers[i] + r * np.stack([np.cos(angles), np.sin(angles)], -1))
    cv2.polylines(image, [hull.astype(np.int32)], True, GOAL, 2, cv2.LINE_AA)
