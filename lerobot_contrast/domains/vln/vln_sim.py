"""The simulated studio apartment as a LeRobot `Robot` in this process: VLN-CE discrete steps in, odometry and the
ray-cast camera out, with the LoCoBot's feature names (from the shared `navigation_protocol`), so a policy for one
runs on the other. It also implements `SceneIO`, so the evaluator stages and judges every trial itself."""

from __future__ import annotations

import math
from typing import Any

from navigation_protocol import CAMERA, DEPTH, DISCRETE_KEYS, POSE_KEYS, STATE_KEYS, discrete_command, one_hot

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.domains.simulated_robot import SimulatedRobot
from lerobot_contrast.domains.vln.config_vln_sim import VLNSimConfig
from lerobot_contrast.domains.vln.locobot_sim import SimBackend


class VLNSim(SimulatedRobot):
    """Each discrete step happens at once: the next observation shows where it ended."""

    config_class = VLNSimConfig
    name = "vln_sim"
    pose_keys = POSE_KEYS
    # Staging places every piece of furniture and the robot and stills it: a sweep may share its episodes.
    stages_whole_state = True

    def __init__(self, config: VLNSimConfig) -> None:
        super().__init__(config)
        self.stop_requested = False  # the last action was "stop": a VLN episode ends here

    @property
    def observation_features(self) -> dict[str, Any]:
        features: dict[str, Any] = dict.fromkeys(STATE_KEYS, float)
        if self.config.camera:
            features[CAMERA] = (self.config.camera_height, self.config.camera_width, 3)
            if self.config.depth:
                features[DEPTH] = (self.config.camera_height, self.config.camera_width, 1)
        return features

    @property
    def action_features(self) -> dict[str, type]:
        return dict.fromkeys(DISCRETE_KEYS, float)

    def _build(self) -> SimBackend:
        apartment = SimBackend(self.config)
        apartment.configure_camera(self.config.camera_width, self.config.camera_height, depth=self.config.depth)
        return apartment

    def get_observation(self) -> dict[str, Any]:
        apartment = self._require()
        x, y, theta = apartment.odometry()
        observation: dict[str, Any] = {"odom.x": x, "odom.y": y, "odom.theta": theta, **apartment.state()}
        if self.config.camera:
            _, rgb, depth = apartment.images()
            observation[CAMERA] = rgb
            if depth is not None:
                observation[DEPTH] = depth[..., None]
        return observation

    def send_action(self, action: dict[str, Any]) -> dict[str, Any]:
        apartment = self._require()
        command = discrete_command(action)
        if command is not None:
            amount = self.config.forward_m if command == "forward" else math.radians(self.config.turn_deg)
            apartment.start_step(command, amount)
            apartment.update(0.0)
            self.stop_requested = command == "stop"
        return one_hot(command)

    def read_scene(self) -> Scene:
        return Scene.from_json(self._require().read_scene())

    def stage_scene(self, scene: Scene) -> None:
        self._require().stage_scene(scene.to_json())
        self.stop_requested = False
