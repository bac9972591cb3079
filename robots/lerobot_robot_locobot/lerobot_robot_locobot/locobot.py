"""Locobot: the LeRobot Robot on the workstation, driving a LoCoBot through its host over ZMQ.

With a host running the simulated apartment it also reads and stages scenes (the SceneIO protocol of
lerobot_contrast), so an evaluation stages instances and judges subgoals without an operator."""

from __future__ import annotations

import logging
import math
from functools import cached_property
from typing import Any

import numpy as np
from lerobot.robots import Robot
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError
from navigation_protocol import CAMERA, DEPTH, POSE_KEYS, STATE_KEYS, discrete_command, one_hot

from lerobot_robot_locobot.actions import action_features, clamp
from lerobot_robot_locobot.config_locobot import LocobotConfig
from lerobot_robot_locobot.link import HostLink, Received
from lerobot_robot_locobot.protocol import decode_depth, decode_rgb

log = logging.getLogger(__name__)


class SceneIOUnavailable(RuntimeError):
    """The host cannot report or stage scenes (a real robot): ask the operator instead."""


class Locobot(Robot):
    config_class = LocobotConfig
    name = "locobot"
    pose_keys = POSE_KEYS

    def __init__(self, config: LocobotConfig) -> None:
        super().__init__(config)
        self.config = config
        shape = (config.camera_height, config.camera_width)
        self.cameras: dict[str, tuple[int, int, int]] = {CAMERA: (*shape, 3)}
        if config.use_depth:
            self.cameras[DEPTH] = (*shape, 1)
        self._link: HostLink | None = None
        self._decoded: tuple[int, dict[str, Any]] | None = None
        self.stop_requested = False  # the last discrete action was "stop": a VLN episode ends here

    @cached_property
    def observation_features(self) -> dict[str, type | tuple]:
        return {**dict.fromkeys(STATE_KEYS, float), **self.cameras}

    @cached_property
    def action_features(self) -> dict[str, type]:
        return action_features(self.config.action_mode)

    @property
    def is_connected(self) -> bool:
        return self._link is not None

    @property
    def is_calibrated(self) -> bool:
        return True

    @property
    def capabilities(self) -> frozenset[str]:
        """What the host offers beyond driving: "scene_io" (sim backend), "set_odometry"."""
        return frozenset() if self._link is None else self._link.capabilities

    @property
    def supports_scene_io(self) -> bool:
        return "scene_io" in self.capabilities

    @property
    def simulated(self) -> bool:
        """The host runs the simulated apartment (scene I/O is offered only there): no need to pace the loop,
        since each discrete step returns once the host has executed it."""
        return self.supports_scene_io

    def connect(self, calibrate: bool = True) -> None:
        if self._link is not None:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        self._link = HostLink(self.config)

    def calibrate(self) -> None:
        """Nothing to calibrate: the host owns the base and the camera."""

    def configure(self) -> None:
        """Nothing to configure: the camera size and depth are agreed in the handshake."""

    def get_observation(self) -> dict[str, Any]:
        return self._decode(self._connected().observation())

    def send_action(self, action: dict[str, Any]) -> dict[str, Any]:
        link = self._connected()
        if self.config.action_mode == "velocity":
            missing = [key for key in self.action_features if key not in action]
            if missing:
                raise ValueError(
                    f"LoCoBot velocity action lacks {missing}; send both x.vel (m/s) and theta.vel (rad/s)"
                )
            x, theta = (
                clamp(action["x.vel"], self.config.max_x_vel),
                clamp(action["theta.vel"], self.config.max_theta_vel),
            )
            link.velocity(x, theta)
            return {"x.vel": x, "theta.vel": theta}
        command = discrete_command(action)
        if command is not None:
            amount = self.config.forward_m if command == "forward" else math.radians(self.config.turn_deg)
            result = link.step(command, 0.0 if command == "stop" else amount).header["ack"]["result"]
            if result != "done":  # the bumper stopped it, or the base did not get there in time
                log.warning("LoCoBot %s step ended %s", command, result)
            self.stop_requested = command == "stop"
        return one_hot(command)

    def disconnect(self) -> None:
        if self._link is None:
            raise DeviceNotConnectedError(f"{self} is not connected")
        self._link.close()
        self._link = None

    def read_scene(self) -> dict[str, Any]:
        """The furniture and the robot's pose, as a scene's JSON (sim backend only)."""
        return self._scene_call("read_scene")["scene"]

    def stage_scene(self, scene: Any) -> None:
        """Place the furniture and the robot as in `scene`; odometry then reads in the scene's frame."""
        self._scene_call("stage_scene", scene=scene.to_json())
        self.stop_requested = False

    def set_odometry(self, x: float, y: float, theta: float) -> None:
        """Make the current odometry read (x, y, theta), e.g. the start pose of an episode in the scene frame."""
        self._connected().call("set_odometry", pose=[x, y, theta])

    def _scene_call(self, op: str, **fields: Any) -> dict[str, Any]:
        link = self._connected()
        if not self.supports_scene_io:
            raise SceneIOUnavailable(
                f"the LoCoBot host at {self.config.host} drives a real robot and cannot {op.replace('_', ' ')}; "
                "stage scenes and judge episodes through the operator instead"
            )
        return link.call(op, **fields)

    def _connected(self) -> HostLink:
        if self._link is None:
            raise DeviceNotConnectedError(f"{self} is not connected; call connect() first")
        return self._link

    def _decode(self, received: Received) -> dict[str, Any]:
        """Floats and images of one observation, decoded once however often it is returned."""
        if self._decoded is None or self._decoded[0] != received.seq:
            state = received.header["state"]
            observation: dict[str, Any] = {key: float(state[key]) for key in STATE_KEYS}
            observation[CAMERA] = self._sized(decode_rgb(received.frames["rgb"]), CAMERA)
            if self.config.use_depth:
                observation[DEPTH] = self._sized(decode_depth(received.frames["depth"])[..., None], DEPTH)
            self._decoded = (received.seq, observation)
        return dict(self._decoded[1])

    def _sized(self, image: np.ndarray, name: str) -> np.ndarray:
        if image.shape != self.cameras[name]:
            raise ValueError(f"the host sent a {image.shape} {name} image, expected {self.cameras[name]}")
        return image
