"""The twin arm's LeRobot calibration file, written from the servos' own registers where `so101_follower` looks for it,
so that `connect()` finds it matching the bus and never asks to calibrate."""

import os
from pathlib import Path

import draccus
from lerobot.motors import MotorCalibration
from lerobot.robots.so_follower import SO101Follower
from lerobot.utils.constants import HF_LEROBOT_CALIBRATION, ROBOTS

from lerobot_contrast.twin.servos import ServoBank


def calibration_path(robot_id: str, calibration_dir: Path | str | None = None) -> Path:
    """Where `--robot.type=so101_follower --robot.id=<robot_id>` reads its calibration (`--robot.calibration_dir`
    when given, else LeRobot's calibration folder, `$HF_LEROBOT_CALIBRATION/robots/so_follower` in LeRobot 0.6)."""
    folder = Path(calibration_dir) if calibration_dir else HF_LEROBOT_CALIBRATION / ROBOTS / SO101Follower.name
    return folder / f"{robot_id}.json"


def bank_calibration(bank: ServoBank) -> dict[str, MotorCalibration]:
    """The calibration LeRobot's `read_calibration` would read from these servos."""
    calibration = {}
    for servo_id in bank.ids:
        memory = bank.memory(servo_id)
        calibration[bank.names[servo_id]] = MotorCalibration(
            id=servo_id,
            drive_mode=0,
            homing_offset=memory.read("Homing_Offset"),
            range_min=memory.read("Min_Position_Limit"),
            range_max=memory.read("Max_Position_Limit"),
        )
    return calibration


def write_calibration_file(bank: ServoBank, robot_id: str, calibration_dir: Path | str | None = None) -> Path:
    """Write the file as LeRobot's `Robot._save_calibration` does; a reader never sees it half written."""
    path = calibration_path(robot_id, calibration_dir)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_suffix(".json.partial")
        with open(partial, "w") as f, draccus.config_type("json"):
            draccus.dump(bank_calibration(bank), f, indent=4)
        os.replace(partial, path)
    except OSError as e:
        raise OSError(
            f"cannot write the twin's calibration file {path}: {e.strerror}; set --robot.calibration_dir "
            "or HF_LEROBOT_CALIBRATION to a folder you can write"
        ) from e
    return path
