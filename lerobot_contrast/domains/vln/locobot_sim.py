"""The simulated studio apartment as a base with a ray-cast RGB-D camera: the LoCoBot host's `sim` backend, and
the engine of the in-process `vln_sim` robot.

The host finds it through the `lerobot_robot_locobot.backends` entry point, so neither package imports the other;
it implements the plugin's small `Backend` protocol structurally (scenes cross it as JSON)."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any, Protocol

import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln.apartment import STUDIO, Apartment, CameraSpec, RayCaster

# Where the robot stands when the host starts, before a client stages a scene.
START = Pose(4.0, 2.6, 0.0)


class ApartmentSettings(Protocol):
    """The host's `--sim.*` section, or the `vln_sim` robot's config."""

    collision: str  # "slide" along an obstacle or "stop" where it touched
    robot_radius: float
    hfov_deg: float
    camera_height_m: float


class SimBackend:
    capabilities = frozenset({"scene_io", "set_odometry"})

    def __init__(self, config: ApartmentSettings) -> None:
        self.config = config
        self.world = Apartment(robot_radius=config.robot_radius, collision=config.collision)
        self.world.set_scene({name: Pose(*pose) for name, pose in STUDIO.items()}, START)
        self.velocity = (0.0, 0.0)
        self.depth = False
        self._caster = self._camera(640, 480)
        self._finished: str | None = None
        self._rendered: tuple[Hashable, np.ndarray, np.ndarray] | None = None

    def _camera(self, width: int, height: int) -> RayCaster:
        spec = CameraSpec(width, height, self.config.hfov_deg, self.config.camera_height_m)
        return RayCaster(spec)

    def configure_camera(self, width: int, height: int, depth: bool) -> None:
        if (width, height) != (self._caster.spec.width, self._caster.spec.height):
            self._caster = self._camera(width, height)
        self.depth = depth

    def start_step(self, command: str, amount: float) -> None:
        """Steps happen at once: the robot's next observation shows where the step ended."""
        self.velocity = (0.0, 0.0)
        if command == "forward":
            self.world.forward(amount)
        elif command in ("turn_left", "turn_right"):
            self.world.rotate(amount if command == "turn_left" else -amount)
        self._finished = "done"

    def set_velocity(self, x: float, theta: float) -> None:
        self.velocity = (x, theta)

    def update(self, dt: float) -> str | None:
        if self.moving:
            self.world.drive(*self.velocity, dt)
        finished, self._finished = self._finished, None
        return finished

    def stop(self) -> bool:
        self.velocity = (0.0, 0.0)
        return False

    @property
    def moving(self) -> bool:
        return self.velocity != (0.0, 0.0)

    def odometry(self) -> tuple[float, float, float]:
        pose = self.world.pose
        return (pose.x, pose.y, pose.yaw)

    def state(self) -> dict[str, float]:
        return {"x.vel": self.velocity[0], "theta.vel": self.velocity[1], "bumper": float(self.world.bumped)}

    def images(self) -> tuple[Hashable, np.ndarray, np.ndarray | None]:
        spec = self._caster.spec
        key = (self.world.pose, self.world.version, spec.width, spec.height)
        if self._rendered is None or self._rendered[0] != key:
            rgb, depth = self._caster.render(self.world.room, self.world.footprints, self.world.pose)
            self._rendered = (key, rgb, depth)
        _, rgb, depth = self._rendered
        return (key, self.depth), rgb, depth if self.depth else None

    def read_scene(self) -> dict[str, Any]:
        return self.world.scene().to_json()

    def stage_scene(self, scene: dict[str, Any]) -> None:
        staged = Scene.from_json(scene)
        self.velocity = (0.0, 0.0)
        self.world.set_scene(staged.objects, staged.robot)

    def close(self) -> None:
        self.velocity = (0.0, 0.0)
