"""Host backends: what moves the base and makes the images. `sim` (the simulated apartment) or `ros2` (an
Interbotix LoCoBot); each is imported only when selected, so the robot needs no simulator and vice versa."""

from __future__ import annotations

from collections.abc import Hashable
from importlib.metadata import entry_points
from typing import Any, Protocol

import numpy as np

from lerobot_robot_locobot.config_host import BACKENDS
from lerobot_robot_locobot.odometry import Pose2

# Backends other packages provide: name = "module:Class", built from the host config's section of that name.
BACKEND_GROUP = "lerobot_robot_locobot.backends"


class Backend(Protocol):
    """The host's view of a base with a camera. The host calls `update` every loop iteration."""

    # "scene_io": read_scene/stage_scene work (simulation); "set_odometry": odometry can be re-anchored.
    capabilities: frozenset[str]

    def configure_camera(self, width: int, height: int, depth: bool) -> None: ...

    def start_step(self, command: str, amount: float) -> None:
        """Begin a discrete step: forward `amount` metres, turn_left/turn_right `amount` radians, or stop."""
        ...

    def set_velocity(self, x: float, theta: float) -> None: ...

    def update(self, dt: float) -> str | None:
        """Advance `dt` seconds; the result of a step that finished now ("done", "blocked", "timeout")."""
        ...

    def stop(self) -> bool:
        """Stop the base at once; True if this abandoned a running step."""
        ...

    @property
    def moving(self) -> bool: ...

    def odometry(self) -> Pose2: ...

    def state(self) -> dict[str, float]:
        """Measured or commanded "x.vel", "theta.vel", and "bumper" (1.0 while in contact)."""
        ...

    def images(self) -> tuple[Hashable, np.ndarray, np.ndarray | None]:
        """A key that changes whenever the images do, RGB (H, W, 3) uint8 and depth (H, W) metres or None."""
        ...

    def read_scene(self) -> dict[str, Any]: ...

    def stage_scene(self, scene: dict[str, Any]) -> None: ...

    def close(self) -> None: ...


def make_backend(name: str, config: Any) -> Backend:
    """The backend `name` built from the host config's section of the same name."""
    if name == "sim":  # provided by lerobot_contrast, found by entry point so that this package never imports it
        found = entry_points(group=BACKEND_GROUP, name="sim")
        if not found:
            raise ImportError("--backend=sim needs the lerobot_contrast package; install it or use --backend=ros2")
        return next(iter(found)).load()(config.sim)
    if name == "ros2":
        from lerobot_robot_locobot.backend_ros2 import Ros2Backend

        return Ros2Backend(config.ros2)
    raise ValueError(f"--backend must be one of {list(BACKENDS)}, got {name!r}")
