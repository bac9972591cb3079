"""`python -m lerobot_contrast.calibrate`: find the printed ArUco board lying on the table in each camera's view and
store the lens and the table-to-pixel homography (<task>.calibration.json: beside your task file, or for a shipped
example in LeRobot's calibration folder under tables/), where eval's staging finds it, for staging overlays and checks.

`--write_board=board.pdf` writes the board to print (its printed size is stated on it and here).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from lerobot.robots import RobotConfig

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.spine.flags import (
    ConfigError,
    bool_flags,
    check_names,
    flag_types,
    help_text,
    join_values,
    parse_config,
    robot_type,
    wants_help,
)
from lerobot_contrast.staging.board import BoardArgs, printed_size_text, write_page

COMMAND = "python -m lerobot_contrast.calibrate"


@dataclass
class CalibrateConfig:
    """Calibrate the table plane to each camera from the printed ArUco board lying on the table."""

    # The task whose table this is: a shipped task file by name (so101_blocks) or a task file's path.
    task: str = "so101_blocks"
    # The robot whose cameras see the table, with eval's --robot.* flags (e.g. so101_follower and its cameras).
    robot: RobotConfig | None = None
    # Calibrate from a saved camera frame (PNG/JPEG) instead of a robot's cameras.
    image: Path | None = None
    # The camera the --image was taken with (its observation key in eval).
    camera: str = "top"
    # Where the board's centre lies on the table: --board.x=0.30 --board.y=0 (metres) --board.yaw_deg=0.
    board: BoardArgs = field(default_factory=BoardArgs)
    # The calibration file to write (default: <task>.calibration.json beside your task file; for a shipped example,
    # tables/<task>.calibration.json in LeRobot's calibration folder, $HF_LEROBOT_CALIBRATION). eval finds either.
    output: Path | None = None
    # Whose time the robot runs on: wall, or a twin's simulated clock (tcp://HOST:PORT, as eval's --clock).
    clock: str = "wall"
    # Refuse a fit whose RMS reprojection error is above this many pixels (a positive number).
    max_error_px: float = 2.0
    # Write the printable board to this .pdf or .png and exit.
    write_board: Path | None = None


def frames(cfg: CalibrateConfig) -> dict[str, np.ndarray]:
    """The RGB frames to calibrate: the --image, or one from each of the robot's cameras."""
    if cfg.image is not None:
        import cv2

        image = cv2.imread(str(cfg.image), cv2.IMREAD_COLOR) if cfg.image.is_file() else None
        if image is None:
            raise UserError(f"--image={cfg.image}: cannot read it as an image; give a PNG or JPEG camera frame")
        return {cfg.camera: cv2.cvtColor(image, cv2.COLOR_BGR2RGB)}
    if cfg.robot is None:
        raise ConfigError("give --robot.type=... (with its cameras) or --image=FRAME.png to calibrate from")
    from lerobot.robots import make_robot_from_config

    from lerobot_contrast.eval import connect

    try:
        robot = make_robot_from_config(cfg.robot)
    except Exception as error:
        raise ConfigError(
            f"--robot.type={cfg.robot.type}: cannot build the robot ({' '.join(str(error).split())})"
        ) from None
    connect(robot, cfg.clock)
    try:
        return camera_frames(robot)
    finally:
        robot.disconnect()


def camera_frames(robot: Any) -> dict[str, np.ndarray]:
    from lerobot_contrast.clock.robot_clock import robot_clock

    robot_clock().look()  # a frame of the board as it now lies
    observation = robot.get_observation()
    found = {k: np.asarray(v) for k, v in observation.items() if getattr(v, "ndim", 0) == 3 and v.shape[-1] == 3}
    if not found:
        raise UserError(f"--robot.type={robot.name}: the robot has no camera; add one with --robot.cameras=...")
    return found


def calibrate(cfg: CalibrateConfig, images: dict[str, np.ndarray]) -> Path:
    """Fit each camera's lens and homography, write the calibration file, and say how well each fits."""
    from lerobot_contrast.domains import load_task
    from lerobot_contrast.staging.homography import CalibrationError, fit, save
    from lerobot_contrast.staging.setup import default_calibration, geometry

    output = cfg.output or default_calibration(cfg.task)
    if output is None:
        raise ConfigError(f"--task={cfg.task} is not a task file; name the calibration file with --output=PATH")
    workspace = geometry(load_task(cfg.task), 0.0).bounds  # where the lens must be known well enough
    fitted, failed = [], []
    for camera, image in images.items():
        try:
            fitted.append(fit(camera, image, cfg.board, cfg.max_error_px, workspace))
        except CalibrationError as error:
            failed.append(str(error))
    if not fitted:
        raise CalibrationError("; ".join(failed))
    try:
        save(output, fitted, cfg.board)
    except OSError as error:
        raise UserError(f"cannot write {output} ({error.strerror}); name another file with --output=PATH") from None
    for calibration in fitted:
        lens = calibration.lens
        print(
            f"camera {calibration.camera}: {calibration.markers} markers, reprojection error {calibration.error_px:.2f} "
            f"px, lens k1 {lens.k1:+.3f} (+-{lens.k1_sigma:.3f}), focal length {lens.focal:.0f} px"
        )
    for line in failed:
        print(f"skipped: {line}")
    found = "" if cfg.output is not None else f"; eval --task={cfg.task} finds it there"
    print(f"wrote {output}{found}")
    return output


def main(argv: list[str] | None = None) -> int:
    from lerobot_contrast.spine.build import check_robot_type, register_robots

    try:
        argv = join_values(list(sys.argv[1:] if argv is None else argv), bool_flags(CalibrateConfig))
        if not wants_help(argv):
            check_names(argv, flag_types(CalibrateConfig), robots=False)
        if wants_help(argv) or any(arg.startswith("--robot.") for arg in argv):  # LeRobot's robots load slowly
            check_robot_type(argv, register_robots())
        if wants_help(argv):
            print(help_text(CalibrateConfig, COMMAND, robot_type(argv)))
            print(f"\nThe board: {printed_size_text()}.")
            return 0
        cfg = parse_config(CalibrateConfig, argv)
        if not cfg.max_error_px > 0:  # NaN too
            raise ConfigError(f"--max_error_px={cfg.max_error_px:g}: give a positive number of pixels (default 2)")
        if cfg.write_board is not None:
            print(write_page(cfg.write_board))
            return 0
        calibrate(cfg, frames(cfg))
        return 0
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
