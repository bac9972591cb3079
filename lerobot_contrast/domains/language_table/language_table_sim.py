"""The Language-Table-compatible tabletop as a LeRobot `Robot`: camera and effector state out, effector deltas in.

It also implements `SceneIO`, so the evaluator (or the operator, by answering prompts) stages block
layouts and judges goals from the block poses, exactly as a perception-equipped real set-up would.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.physics import TabletopPhysics
from lerobot_contrast.domains.simulated_robot import SimulatedRobot

CAMERA = "top"
STATE = ("effector.x", "effector.y", "effector_target.x", "effector_target.y")
ACTION = ("delta_x", "delta_y")


def episode_features(camera: bool = True) -> dict[str, dict[str, Any]]:
    """The robot's observation and action features, as episode observers receive them."""
    observation: dict[str, Any] = dict.fromkeys(STATE, float)
    if camera:
        observation[CAMERA] = (board.IMAGE_HEIGHT, board.IMAGE_WIDTH, 3)
    return {"observation": observation, "action": dict.fromkeys(ACTION, float)}


class LanguageTableSim(SimulatedRobot):
    config_class = LanguageTableSimConfig
    name = "language_table_sim"
    stageable_objects = board.ALL_BLOCKS
    # Observation keys holding the effector's planar position in the scene frame.
    pose_keys = ("effector.x", "effector.y")
    # Staging rebuilds the whole world from the scene (zero velocities), so an episode depends on nothing a previous
    # one left: cells of a sweep may share it (record/shared_episodes.py).
    stages_whole_state = True

    def __init__(self, config: LanguageTableSimConfig) -> None:
        super().__init__(config)
        self._renderer = None

    @property
    def observation_features(self) -> dict[str, Any]:
        return episode_features(self.config.camera)["observation"]

    @property
    def action_features(self) -> dict[str, type]:
        return episode_features()["action"]

    def _build(self) -> TabletopPhysics:
        physics = TabletopPhysics()
        physics.set_state({}, (board.CENTER_X, board.CENTER_Y))
        return physics

    def get_observation(self) -> dict[str, Any]:
        physics = self._require()
        (ex, ey), (tx, ty) = physics.effector, physics.target
        observation: dict[str, Any] = dict(zip(STATE, (ex, ey, tx, ty), strict=True))
        if self.config.camera:
            observation[CAMERA] = self._render(physics)
        return observation

    def _render(self, physics: TabletopPhysics) -> np.ndarray:
        if self._renderer is None:  # imported on first use: camera-less rollouts never load cv2
            from lerobot_contrast.domains.language_table.render import TabletopRenderer

            self._renderer = TabletopRenderer(board.IMAGE_HEIGHT, board.IMAGE_WIDTH)
        blocks, effector = physics.state()
        return self._renderer.render(blocks, effector)

    def send_action(self, action: dict[str, Any]) -> dict[str, Any]:
        physics = self._require()
        delta = np.clip([float(action[key]) for key in ACTION], -board.MAX_ACTION, board.MAX_ACTION)
        physics.step(delta)
        return dict(zip(ACTION, delta.tolist(), strict=True))

    def read_scene(self) -> Scene:
        blocks, (ex, ey) = self._require().state()
        return Scene(objects={name: Pose(*pose) for name, pose in blocks.items()}, robot=Pose(ex, ey))

    def stage_scene(self, scene: Scene) -> None:
        unknown = sorted(set(scene.objects) - set(board.ALL_BLOCKS))
        if unknown:
            raise UserError(
                f"--robot.type=language_table_sim can only place Language-Table blocks, not {', '.join(unknown)}; "
                "evaluate this task on a robot that matches its objects"
            )
        robot = scene.robot or Pose(board.CENTER_X, board.CENTER_Y)
        blocks = {name: (pose.x, pose.y, pose.yaw) for name, pose in scene.objects.items()}
        self._require().set_state(blocks, (robot.x, robot.y))
