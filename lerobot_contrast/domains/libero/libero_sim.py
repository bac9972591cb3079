"""LeRobot's LIBERO environment (`lerobot.envs.libero.LiberoEnv`) as a LeRobot `Robot` with `SceneIO`: LIBERO's
two cameras and the 8-number state its policies read (through LeRobot's own `LiberoProcessorStep`) out, the 7-number
end-effector action in; the evaluator stages object layouts in it and judges goals with LIBERO's predicates."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.domains.libero import judge, staging
from lerobot_contrast.domains.libero.config_libero_sim import LiberoSimConfig
from lerobot_contrast.domains.simulated_robot import SimulatedRobot

CAMERAS = ("image", "image2")  # agent view and wrist, as LeRobot names them
STATE = ("eef.x", "eef.y", "eef.z", "eef.ax", "eef.ay", "eef.az", "gripper.left", "gripper.right")
ACTION = ("eef.dx", "eef.dy", "eef.dz", "eef.droll", "eef.dpitch", "eef.dyaw", "gripper")


class LiberoSim(SimulatedRobot):
    config_class = LiberoSimConfig
    name = "libero_sim"
    pose_keys = ("eef.x", "eef.y")
    # Staged objects settle in MuJoCo's physics: the runner charges the distances read back after settling.
    measures_staging = True

    def __init__(self, config: LiberoSimConfig) -> None:
        super().__init__(config)
        self._processor = None

    @property
    def observation_features(self) -> dict[str, Any]:
        features: dict[str, Any] = dict.fromkeys(STATE, float)
        if self.config.camera:
            for camera in CAMERAS:
                features[camera] = (self.config.observation_height, self.config.observation_width, 3)
        return features

    @property
    def action_features(self) -> dict[str, type]:
        return dict.fromkeys(ACTION, float)

    def _build(self) -> staging.World:
        from lerobot_contrast.domains.libero import runtime

        runtime.load()
        world = staging.World(self.config)
        judge.attach(self)
        return world

    def disconnect(self) -> None:
        self._require().close()
        judge.detach(self)
        super().disconnect()

    def get_observation(self) -> dict[str, Any]:
        world = self._require()
        if self._processor is None:
            from lerobot.processor.env_processor import LiberoProcessorStep

            self._processor = LiberoProcessorStep()
        return observation(world.observation(), self._processor, self.config.camera)

    def send_action(self, action: dict[str, Any]) -> dict[str, Any]:
        vector = np.clip(np.array([float(action[key]) for key in ACTION], dtype=np.float32), -1.0, 1.0)
        self._require().step(vector)
        return dict(zip(ACTION, vector.tolist(), strict=True))

    def read_scene(self) -> Scene:
        world = self._require()
        return Scene(objects=world.poses()) if world.env is not None else Scene()

    def stage_scene(self, scene: Scene) -> None:
        self._require().stage(scene)

    def goal_holds(self, goal: Sequence[Sequence[str]]) -> bool:
        """LIBERO's own verdict on BDDL predicates (what `check_success` evaluates for the task's goal)."""
        inner = self._require().inner()
        try:
            return all(bool(inner._eval_predicate(list(predicate))) for predicate in goal)
        except (KeyError, AttributeError) as error:
            raise UserError(
                f"the LIBERO scene cannot judge {goal} ({error}); the goal names a place it lacks"
            ) from None


def observation(raw: dict[str, Any], processor: Any, camera: bool) -> dict[str, Any]:
    """LeRobot's LIBERO observation after its own processor step (images turned 180°, state = eef pos, axis-angle,
    gripper), as a robot's flat dict of HxWx3 uint8 frames and floats."""
    from lerobot.envs.utils import preprocess_observation

    batched = {
        "pixels": {name: np.ascontiguousarray(image)[None] for name, image in raw["pixels"].items()},
        "robot_state": {
            part: {key: np.asarray(value)[None] for key, value in fields.items()}
            for part, fields in raw["robot_state"].items()
        },
    }
    processed = processor._process_observation(preprocess_observation(batched))
    state = processed["observation.state"][0].tolist()
    out: dict[str, Any] = dict(zip(STATE, (float(v) for v in state), strict=True))
    if camera:
        for name in CAMERAS:
            image = processed[f"observation.images.{name}"][0]
            out[name] = (image.permute(1, 2, 0).numpy() * 255.0).round().astype(np.uint8)
    return out
