"""A gymnasium env with the Language-Table benchmark's action and observation interface on pymunk physics.

Each episode is one contrast `Instance`, passed as `reset(options={"instance": ...})`. Importing this module
registers the env as `lerobot_contrast/LanguageTable-v0`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import LanguageTableTask, board, instruction_to_array
from lerobot_contrast.domains.language_table.physics import TabletopPhysics

# The benchmark pays 100 on success; 1.0 makes the summed episode reward the success indicator.
SUCCESS_REWARD = 1.0
OBS_TYPES = ("rgb", "state")


def _observation_space(obs_type: str) -> spaces.Dict:
    (x_min, y_min), (x_max, y_max) = board.WORKSPACE_BOUNDS
    # The benchmark declares the translations inside the workspace widened by 0.1 m.
    low = np.array([x_min - 0.1, y_min - 0.1], dtype=np.float32)
    high = np.array([x_max + 0.1, y_max + 0.1], dtype=np.float32)
    fields = {
        "effector_translation": spaces.Box(low, high, (2,), np.float32),
        "effector_target_translation": spaces.Box(low, high, (2,), np.float32),
        "instruction": spaces.Box(0, 2**31 - 1, (board.INSTRUCTION_LENGTH,), np.int32),
    }
    if obs_type == "rgb":
        fields["rgb"] = spaces.Box(0, 255, (board.IMAGE_HEIGHT, board.IMAGE_WIDTH, 3), np.uint8)
    return spaces.Dict(fields)


class LanguageTableEnv(gym.Env):
    """Push blocks on the Language-Table board with 2-D effector-target deltas (metres, 10 Hz).

    obs_type "state" leaves out the camera image, for fast scripted rollouts. Without an instance in
    `reset` options, one is sampled from the task (of `family` when given) with the reset seed.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": int(board.CONTROL_HZ)}

    def __init__(
        self,
        block_mode: str = "BLOCK_8",
        render_mode: str | None = None,
        obs_type: str = "rgb",
        family: str | None = None,
    ) -> None:
        if obs_type not in OBS_TYPES:
            raise ValueError(f"unknown obs_type {obs_type!r}; choose from: {', '.join(OBS_TYPES)}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"unknown render_mode {render_mode!r}; choose None or 'rgb_array'")
        self.block_mode, self.obs_type, self.render_mode, self.family = block_mode, obs_type, render_mode, family
        self.task_model = LanguageTableTask(block_mode=block_mode, families=None if family is None else (family,))
        self.observation_space = _observation_space(obs_type)
        self.action_space = spaces.Box(-board.MAX_ACTION, board.MAX_ACTION, (2,), np.float32)
        self._max_episode_steps = board.MAX_EPISODE_STEPS
        self.physics = TabletopPhysics()
        self._renderer = None
        self._frame: np.ndarray | None = None
        self._instance: Instance | None = None
        self.task = self.task_description = ""

    @property
    def instance(self) -> Instance:
        if self._instance is None:
            raise RuntimeError("call reset() before reading the instance")
        return self._instance

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        instance = (options or {}).get("instance") or self._sample_instance(seed)
        self._instance = instance
        self.task = self.task_description = instance.instruction
        self._instruction = instruction_to_array(instance.instruction)
        blocks = {name: (pose.x, pose.y, pose.yaw) for name, pose in instance.scene.objects.items()}
        robot = instance.scene.robot or Pose(board.CENTER_X, board.CENTER_Y)
        self.physics.set_state(blocks, (robot.x, robot.y))
        return self._observation(), {"is_success": self._is_success()}

    def _sample_instance(self, seed: int | None) -> Instance:
        rng = np.random.default_rng(seed if seed is not None else self.np_random.integers(2**63))
        return self.task_model.sample(1, rng)[0]

    def step(self, action: np.ndarray) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        self.physics.step(action)
        success = self._is_success()
        reward = SUCCESS_REWARD if success else 0.0
        return self._observation(), reward, success, False, {"is_success": success}

    def _is_success(self) -> bool:
        return bool(self.task_model.is_achieved(self.instance, self.scene()))

    def scene(self) -> Scene:
        """The current block poses and effector position, as the scene the robot leaves behind."""
        blocks, (ex, ey) = self.physics.state()
        return Scene(objects={name: Pose(*pose) for name, pose in blocks.items()}, robot=Pose(ex, ey))

    def _observation(self) -> dict[str, np.ndarray]:
        self._frame = None
        obs = {
            "effector_translation": np.array(self.physics.effector, dtype=np.float32),
            "effector_target_translation": np.array(self.physics.target, dtype=np.float32),
            "instruction": self._instruction.copy(),
        }
        if self.obs_type == "rgb":
            obs["rgb"] = self.render()
        return obs

    def render(self) -> np.ndarray:
        """The camera frame (180, 320, 3) uint8 of the current state, rendered at most once per step."""
        if self._frame is None:
            if self._renderer is None:  # imported on first use: state-only rollouts never load cv2
                from lerobot_contrast.domains.language_table.render import TabletopRenderer

                self._renderer = TabletopRenderer(board.IMAGE_HEIGHT, board.IMAGE_WIDTH)
            blocks, effector = self.physics.state()
            self._frame = self._renderer.render(blocks, effector)
        return self._frame


LANGUAGE_TABLE_ID = "lerobot_contrast/LanguageTable-v0"

if LANGUAGE_TABLE_ID not in gym.registry:
    gym.register(id=LANGUAGE_TABLE_ID, entry_point=LanguageTableEnv, max_episode_steps=board.MAX_EPISODE_STEPS)
