"""The `ros2` backend: an Interbotix LoCoBot, each discrete step driven closed-loop on its odometry.

The ROS side sits behind `BaseDriver` (velocity out; odometry, bumper and camera images in). The real driver,
`InterbotixDriver`, is imported only when the backend is built without one, so tests run the motion logic
against a fake driver with no ROS installed."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Hashable
from typing import Any, Protocol

import cv2
import numpy as np

from lerobot_robot_locobot.config_host import Ros2Config
from lerobot_robot_locobot.motion import Motion, MotionLimits
from lerobot_robot_locobot.odometry import Pose2


class BaseDriver(Protocol):
    def command_velocity(self, x: float, theta: float) -> None: ...

    def odometry(self) -> Pose2 | None:
        """The latest (x, y, theta) in the base's odom frame; None before the first message."""
        ...

    def bumper(self) -> bool: ...

    def color(self) -> tuple[int, np.ndarray] | None:
        """(message count, RGB image) of the latest colour frame; None before the first."""
        ...

    def depth(self) -> np.ndarray | None:
        """The latest depth frame aligned to colour, metres."""
        ...

    def shutdown(self) -> None: ...


class SceneIONotSupported(RuntimeError):
    pass


class Ros2Backend:
    capabilities = frozenset({"set_odometry"})

    def __init__(
        self, config: Ros2Config, driver: BaseDriver | None = None, clock: Callable[[], float] = time.monotonic
    ) -> None:
        if driver is None:
            from lerobot_robot_locobot.backend_interbotix import InterbotixDriver

            driver = InterbotixDriver(config)
        self.driver, self.clock = driver, clock
        self.limits = MotionLimits(
            x_vel=config.step_x_vel,
            theta_vel=config.step_theta_vel,
            tolerance_m=config.tolerance_m,
            tolerance_rad=math.radians(config.tolerance_deg),
            timeout_s=config.step_timeout_s,
        )
        self.size, self.depth = (640, 480), False
        self.velocity = (0.0, 0.0)
        self.motion: Motion | None = None
        self._finished: str | None = None  # a step that ended without motion (stop), reported by update

    def configure_camera(self, width: int, height: int, depth: bool) -> None:
        self.size, self.depth = (width, height), depth

    def start_step(self, command: str, amount: float) -> None:
        self.velocity = (0.0, 0.0)
        if command == "stop":
            self.driver.command_velocity(0.0, 0.0)
            self.motion, self._finished = None, "done"
            return
        kind = "forward" if command == "forward" else "turn"
        target = amount if command != "turn_right" else -amount
        self.motion = Motion(kind, target, self.odometry(), self.clock(), self.limits)

    def set_velocity(self, x: float, theta: float) -> None:
        self.velocity = (x, theta)

    def update(self, dt: float) -> str | None:
        if self._finished is not None:
            finished, self._finished = self._finished, None
            return finished
        if self.motion is not None:
            command = self.motion.update(self.odometry(), self.clock(), self.driver.bumper())
            if isinstance(command, str):
                self.driver.command_velocity(0.0, 0.0)
                self.motion = None
                return command
            self.driver.command_velocity(*command)
        elif self.moving:  # the base's own safety stop needs a steady command stream
            self.driver.command_velocity(*self.velocity)
        return None

    def stop(self) -> bool:
        aborted = self.motion is not None
        self.motion, self.velocity = None, (0.0, 0.0)
        self.driver.command_velocity(0.0, 0.0)
        return aborted

    @property
    def moving(self) -> bool:
        return self.motion is not None or self.velocity != (0.0, 0.0)

    def odometry(self) -> Pose2:
        pose = self.driver.odometry()
        return (0.0, 0.0, 0.0) if pose is None else pose

    def state(self) -> dict[str, float]:
        return {"x.vel": self.velocity[0], "theta.vel": self.velocity[1], "bumper": float(self.driver.bumper())}

    def images(self) -> tuple[Hashable, np.ndarray, np.ndarray | None]:
        """The latest camera frames at the client's size (black until the camera's first frame)."""
        width, height = self.size
        color = self.driver.color()
        if color is None:
            return ("no camera", self.size), np.zeros((height, width, 3), np.uint8), None
        count, rgb = color
        rgb = (
            cv2.resize(rgb, (width, height), interpolation=cv2.INTER_AREA) if rgb.shape[:2] != (height, width) else rgb
        )
        depth = self.driver.depth() if self.depth else None
        if depth is not None and depth.shape != (height, width):
            depth = cv2.resize(depth, (width, height), interpolation=cv2.INTER_NEAREST)
        return (count, self.size, self.depth), rgb, depth

    def read_scene(self) -> dict[str, Any]:
        raise SceneIONotSupported("read_scene needs the sim backend; on the robot the operator reports the scene")

    def stage_scene(self, scene: dict[str, Any]) -> None:
        raise SceneIONotSupported("stage_scene needs the sim backend; on the robot the operator stages the scene")

    def close(self) -> None:
        self.stop()
        self.driver.shutdown()
