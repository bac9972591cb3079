"""`--teleop.type=so101_demo`: the scripted demonstrator's settings."""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.teleoperators.config import TeleoperatorConfig

from lerobot_contrast.so101 import DEFAULT_PACE
from lerobot_contrast.twin.placement_client import DEFAULT_ADDRESS


@TeleoperatorConfig.register_subclass("so101_demo")
@dataclass(kw_only=True)
class SO101DemoConfig(TeleoperatorConfig):
    """A scripted operator for the virtual SO-101 (`python -m lerobot_contrast.twin`): reads the twin's true scene and
    the instruction, and moves the arm through inverse kinematics; places the objects anew for every episode."""

    # The twin's placement socket, as `python -m lerobot_contrast.twin` prints it.
    placement: str = DEFAULT_ADDRESS
    # The task file the twin was started with (a path or a shipped example's name).
    task: str = "so101_blocks"
    # What to do; default: the recorded task, --dataset.single_task.
    instruction: str | None = None
    # Seconds of one recorded episode; default: --dataset.episode_time_s (the reset period starts after it).
    episode_time_s: float | None = None
    # Seeds the objects' placements: episode k of seed s is placed the same way on every run.
    seed: int = 0
    # The number of the first episode (a resumed recording continues the placements where it stopped).
    first_episode: int = 0
    # Each motion's time, as a multiple of the planned one (larger: slower, surer on a loaded machine).
    pace: float = DEFAULT_PACE
