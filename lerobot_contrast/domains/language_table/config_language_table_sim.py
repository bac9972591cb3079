"""`--robot.type=language_table_sim`: the Language-Table-compatible tabletop as a LeRobot robot."""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.robots import RobotConfig


@RobotConfig.register_subclass("language_table_sim")
@dataclass(kw_only=True)
class LanguageTableSimConfig(RobotConfig):
    # Render the overhead camera `top` (180x320 RGB). Scripted policies that read the scene need no image.
    camera: bool = True
