"""LeRobot robot plugin for the LoCoBot: `--robot.type=locobot` (the workstation client), the host that runs on
the robot (`python -m lerobot_robot_locobot.host`, ROS 2 or simulated backend) and its one wire protocol, and
`--teleop.type=locobot_keyboard`. LeRobot imports this distribution at start-up (name prefix `lerobot_robot_`)."""

from navigation_protocol import COMMANDS, DISCRETE_KEYS, POSE_KEYS, is_stop, one_hot

from lerobot_robot_locobot.actions import VELOCITY_KEYS
from lerobot_robot_locobot.config_locobot import LocobotConfig
from lerobot_robot_locobot.config_locobot_keyboard import LocobotKeyboardConfig
from lerobot_robot_locobot.link import LocobotConnectionError, LocobotHostError
from lerobot_robot_locobot.locobot import Locobot, SceneIOUnavailable
from lerobot_robot_locobot.locobot_keyboard import LocobotKeyboard

__version__ = "0.1.0"

__all__ = [
    "COMMANDS",
    "DISCRETE_KEYS",
    "POSE_KEYS",
    "VELOCITY_KEYS",
    "Locobot",
    "LocobotConfig",
    "LocobotConnectionError",
    "LocobotHostError",
    "LocobotKeyboard",
    "LocobotKeyboardConfig",
    "SceneIOUnavailable",
    "is_stop",
    "one_hot",
]
