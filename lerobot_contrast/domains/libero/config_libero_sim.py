"""`--robot.type=libero_sim`: LeRobot's LIBERO environment (`lerobot.envs.libero`) as an in-process LeRobot robot."""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.robots import RobotConfig

from lerobot_contrast.contrast.errors import UserError


@RobotConfig.register_subclass("libero_sim")
@dataclass(kw_only=True)
class LiberoSimConfig(RobotConfig):
    # Render the two cameras (`image`: agent view, `image2`: wrist). LIBERO always renders them; this flag only
    # says whether they reach the policy and the recordings.
    camera: bool = True
    # The camera size; LeRobot's `--env.type=libero` default is 360x360, and its LIBERO checkpoints resize.
    observation_width: int = 360
    observation_height: int = 360
    # Control periods of physics after staging a scene, the arm held still, so objects come to rest before the trial
    # (LeRobot's own reset waits as many no-op steps).
    settle_steps: int = 10

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (16 <= self.observation_width <= 1024 and 16 <= self.observation_height <= 1024):
            raise UserError(
                "--robot.observation_width and --robot.observation_height must be between 16 and 1024 pixels, "
                f"got {self.observation_width}x{self.observation_height}"
            )
        if self.settle_steps < 0:
            raise UserError(f"--robot.settle_steps must be 0 or more, got {self.settle_steps}")
