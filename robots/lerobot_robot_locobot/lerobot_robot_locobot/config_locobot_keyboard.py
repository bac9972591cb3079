"""`--teleop.type=locobot_keyboard`: drive the LoCoBot from the keyboard, e.g. to record data with lerobot-record."""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.teleoperators.config import TeleoperatorConfig

from lerobot_robot_locobot.actions import ACTION_MODES


@TeleoperatorConfig.register_subclass("locobot_keyboard")
@dataclass
class LocobotKeyboardConfig(TeleoperatorConfig):
    # Must match --robot.action_mode: "discrete" (one step per key press) or "velocity" (hold keys to drive).
    action_mode: str = "discrete"
    # Velocity mode: speeds while w/s (forward/back) or a/d (turn left/right) is held.
    x_vel: float = 0.2
    theta_vel: float = 0.6

    def __post_init__(self) -> None:
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"--teleop.action_mode must be one of {list(ACTION_MODES)}, got {self.action_mode!r}")
