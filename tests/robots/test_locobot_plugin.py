"""LeRobot discovers the plugin: the locobot robot and the locobot_keyboard teleoperator, with float features."""

from __future__ import annotations

import subprocess
import sys

from lerobot.robots import make_robot_from_config
from lerobot.teleoperators import make_teleoperator_from_config
from lerobot.utils.import_utils import register_third_party_plugins
from lerobot_robot_locobot import Locobot, LocobotConfig, LocobotKeyboard, LocobotKeyboardConfig
from lerobot_robot_locobot.locobot_keyboard import keys_to_action


def test_lerobot_registers_the_plugin_and_builds_the_client_from_its_config(tmp_path):
    register_third_party_plugins()
    robot = make_robot_from_config(LocobotConfig(host="192.168.1.20", calibration_dir=tmp_path))
    assert isinstance(robot, Locobot) and not robot.is_connected
    assert robot.pose_keys == ("odom.x", "odom.y") and set(robot.cameras) == {"front"}
    assert robot.action_features == dict.fromkeys(["forward.vel", "turn_left.vel", "turn_right.vel", "stop.vel"], float)
    floats = [k for k, v in robot.observation_features.items() if v is float]
    assert floats == ["odom.x", "odom.y", "odom.theta", "x.vel", "theta.vel", "bumper"]
    assert not any(key.endswith(".pos") for key in robot.observation_features)  # rollout would drive "back" to them
    assert robot.observation_features["front"] == (480, 640, 3)


def test_a_fresh_interpreter_finds_both_choices_after_plugin_discovery():
    code = (
        "from lerobot.utils.import_utils import register_third_party_plugins\n"
        "from lerobot.robots import RobotConfig\n"
        "from lerobot.teleoperators.config import TeleoperatorConfig\n"
        "register_third_party_plugins()\n"
        "print(RobotConfig.get_choice_class('locobot').__name__, "
        "TeleoperatorConfig.get_choice_class('locobot_keyboard').__name__)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["LocobotConfig", "LocobotKeyboardConfig"]


def test_the_keyboard_sends_the_robots_action_keys_one_step_per_press(tmp_path):
    teleop = make_teleoperator_from_config(LocobotKeyboardConfig(calibration_dir=tmp_path))
    assert isinstance(teleop, LocobotKeyboard)
    robot = Locobot(LocobotConfig(calibration_dir=tmp_path))
    assert teleop.action_features == robot.action_features
    teleop.events.put(("w", True))
    assert teleop.read_keys()["forward.vel"] == 1.0
    assert set(teleop.read_keys().values()) == {0.0}  # held, not repeated
    teleop.events.put(("w", False))
    teleop.events.put(("d", True))
    assert teleop.read_keys()["turn_right.vel"] == 1.0


def test_the_keyboard_in_velocity_mode_drives_while_keys_are_held():
    config = LocobotKeyboardConfig(action_mode="velocity", x_vel=0.2, theta_vel=0.5)
    assert keys_to_action(config, {"w", "a"}, []) == {"x.vel": 0.2, "theta.vel": 0.5}
    assert keys_to_action(config, {"s", "d"}, []) == {"x.vel": -0.2, "theta.vel": -0.5}
    assert keys_to_action(config, set(), ["w"]) == {"x.vel": 0.0, "theta.vel": 0.0}
