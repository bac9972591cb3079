"""The simulated apartment: furniture, a disc-shaped robot with a continuous pose, and its motion with collisions."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln.apartment.geometry import Footprints, Room, clearance

COLLISION_MODES = ("slide", "stop")
# Translations are checked in sub-steps this long, so the robot never tunnels through a thin object.
SUBSTEP_M = 0.02


def wrap_angle(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


class Apartment:
    """A studio apartment with furniture and a LoCoBot-sized robot.

    On contact the robot either slides along the obstacle (the tangential part of the motion is kept, as in
    Habitat's `ALLOW_SLIDING`) or stops where it touched; either way `bumped` is set until the next motion."""

    def __init__(self, room: Room | None = None, robot_radius: float = 0.18, collision: str = "slide") -> None:
        if collision not in COLLISION_MODES:
            raise ValueError(f"collision must be one of {COLLISION_MODES}, got {collision!r}")
        self.room = room or Room()
        self.robot_radius = robot_radius
        self.collision = collision
        self.objects: dict[str, Pose] = {}
        self.footprints = Footprints.from_objects({})
        self.pose = Pose(self.room.size_x / 2, self.room.size_y / 2, 0.0)
        self.bumped = False
        self.version = 0  # bumped whenever the furniture changes, so renders can be cached

    def set_scene(self, objects: Mapping[str, Pose], robot: Pose | None) -> None:
        """Place the furniture and the robot; refuses furniture outside the room or a robot in collision."""
        footprints = Footprints.from_objects(objects)
        for i, name in enumerate(footprints.names):
            outline = footprints.corners(i) if footprints.is_box[i] else footprints.centers[i : i + 1]
            margin = 0.0 if footprints.is_box[i] else footprints.half[i, 0]
            if (self.room.wall_distance(outline) < margin - 1e-6).any():
                raise ValueError(f"{name} at ({objects[name].x:.2f}, {objects[name].y:.2f}) is outside the room")
        self.objects, self.footprints = dict(objects), footprints
        self.version += 1
        if robot is not None:
            self.place_robot(robot)

    def place_robot(self, pose: Pose) -> None:
        gap = self.clearance(np.array([pose.x, pose.y]))
        if gap < 0:
            raise ValueError(f"robot pose ({pose.x:.2f}, {pose.y:.2f}) collides with {self.nearest(pose)}")
        self.pose = Pose(pose.x, pose.y, wrap_angle(pose.yaw))
        self.bumped = False

    def scene(self) -> Scene:
        return Scene(objects=dict(self.objects), robot=self.pose)

    def clearance(self, xy: np.ndarray) -> float:
        """Free distance around the robot's disc at `xy`; negative when it overlaps a wall or furniture."""
        return float(clearance(self.room, self.footprints, xy)[0]) - self.robot_radius

    def nearest(self, pose: Pose) -> str:
        """What the robot at `pose` is closest to: a furniture name or "a wall"."""
        point = np.array([[pose.x, pose.y]])
        wall = float(self.room.wall_distance(point)[0])
        if len(self.footprints) == 0:
            return "a wall"
        distances = self.footprints.signed_distance(point)[0]
        i = int(distances.argmin())
        return self.footprints.names[i] if distances[i] < wall else "a wall"

    def rotate(self, angle: float) -> None:
        """Turn in place (a disc never collides while turning)."""
        self.pose = Pose(self.pose.x, self.pose.y, wrap_angle(self.pose.yaw + angle))
        self.bumped = False

    def forward(self, distance: float) -> bool:
        """Drive `distance` metres along the heading (negative: backwards); True if it touched something."""
        heading = np.array([math.cos(self.pose.yaw), math.sin(self.pose.yaw)])
        self.bumped = self._translate(heading * distance)
        return self.bumped

    def drive(self, x_vel: float, theta_vel: float, dt: float) -> bool:
        """Integrate body velocities over `dt` seconds (turn, then translate along the new heading)."""
        self.pose = Pose(self.pose.x, self.pose.y, wrap_angle(self.pose.yaw + theta_vel * dt))
        heading = np.array([math.cos(self.pose.yaw), math.sin(self.pose.yaw)])
        self.bumped = self._translate(heading * x_vel * dt)
        return self.bumped

    def _translate(self, motion: np.ndarray) -> bool:
        length = float(np.linalg.norm(motion))
        if length == 0.0:
            return False
        steps = max(1, math.ceil(length / SUBSTEP_M))
        step = motion / steps
        position = np.array([self.pose.x, self.pose.y])
        collided = False
        for _ in range(steps):
            candidate = position + step
            if self.clearance(candidate) < 0:
                collided = True
                if self.collision == "stop":
                    break
                candidate = position + self._slide(position, step)
                if self.clearance(candidate) < 0:
                    break
            position = candidate
        self.pose = Pose(float(position[0]), float(position[1]), self.pose.yaw)
        return collided

    def _slide(self, position: np.ndarray, step: np.ndarray) -> np.ndarray:
        """The part of `step` tangent to the obstacle ahead (normal from the clearance gradient)."""
        probe = position + step
        eps = 1e-3
        grad = np.array(
            [
                self.clearance(probe + [eps, 0.0]) - self.clearance(probe - [eps, 0.0]),
                self.clearance(probe + [0.0, eps]) - self.clearance(probe - [0.0, eps]),
            ]
        )
        norm = float(np.linalg.norm(grad))
        if norm == 0.0:
            return np.zeros(2)
        normal = grad / norm
        into = float(step @ normal)
        return step - min(into, 0.0) * normal
