"""The arm measures its own joints before its first trial (`--arm.measure_joints`): it moves the jaws through views
over the workspace, the calibrated camera finds the purple ball on the fixed jaw in each, and the fit (so101/marker.py)
gives each joint's calibration offset, which the arm then reads and moves through. Kept in the run directory, so a
resumed run measures nothing again."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import cv2
import mujoco
import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.so101 import arm, marker, reach
from lerobot_contrast.so101.marker import JointFit
from lerobot_contrast.so101.motion import ArmMotion
from lerobot_contrast.staging import locate
from lerobot_contrast.staging.homography import CameraCalibration

OFFSETS = "arm_joints.json"
VIEW_MOVE_S = 1.2  # planned seconds from one view to the next (before the pace)
# The ball is searched this near where the model puts it: 3 degrees off at every joint moves it about 50 pixels.
SEARCH_PX = 90.0
# A view counts where the ball shows this share of its disc at least: one the jaw hides in part puts its centroid
# pixels off its centre (measured on the twin: 2 px RMS with every view kept, the jaws fitted 0.5 cm off).
WHOLE = 0.6
OUTLINE_POINTS = 24
MIN_VIEWS = 10  # fewer views seen leave eight numbers poorly fitted
MAX_ERROR_PX = 3.0  # a fit this far off the views is not the arm's offsets: the ball moved, or the camera did
MAX_OFFSET_DEG = 10.0  # LeRobot's calibration puts each joint's middle by eye: further off is not an offset


def measure(motion: ArmMotion, frame: Callable[[], np.ndarray | None], calibration: CameraCalibration) -> JointFit:
    """Move through the calibration views, find the ball in each and fit the offsets; the arm ends at rest. Measured
    with the servos' own readings (whatever offsets `motion` held before)."""
    motion.offsets = {}
    model, data = motion.model, mujoco.MjData(motion.model)
    readings, pixels = [], []
    _, rotation, translation = calibration.pose()
    for goals in marker.poses(model, arm.REST, -rotation.T @ translation):
        motion.follow([reach.Waypoint("view", {**goals, arm.GRIPPER: 0.0}, VIEW_MOVE_S)])
        joints = motion.joints()
        image = frame()
        if image is None:
            continue
        ball = marker.ball_position(model, data, joints, marker.AT)
        expected = calibration.project(ball[None])[0]
        seen = locate.blob_near(image, marker.COLOUR, expected, SEARCH_PX, WHOLE * _disc_pixels(calibration, ball))
        if seen is not None:
            readings.append(joints)
            pixels.append(seen)
    motion.rest()
    if len(readings) < MIN_VIEWS:
        raise UserError(
            f"measuring the arm's joints: the camera saw the {marker.COLOUR} ball on the fixed jaw whole in {len(readings)} "
            f"views, {MIN_VIEWS} are needed; fix a 2 cm {marker.COLOUR} ball there (docs/unattended.md) or pass "
            "--arm.measure_joints=false"
        )
    fitted = marker.fit(model, calibration.project, readings, np.array(pixels))
    worst = max(abs(math.degrees(value)) for value in fitted.offsets.values())
    if fitted.error_px > MAX_ERROR_PX or worst > MAX_OFFSET_DEG:
        raise UserError(
            f"measuring the arm's joints: the fit is {fitted.error_px:.1f} px off the views and puts a joint "
            f"{worst:.1f} degrees off; check the camera's calibration and the ball, or pass --arm.measure_joints=false"
        )
    return fitted


def _disc_pixels(calibration: CameraCalibration, ball: np.ndarray) -> float:
    """The area in pixels of the ball's outline at `ball` (world, m), through the lens."""
    _, rotation, _ = calibration.pose()
    turns = np.linspace(0, 2 * math.pi, OUTLINE_POINTS, endpoint=False)[:, None]
    # Around its centre, square to the camera's axis: the camera's right and down axes in the world.
    outline = ball + marker.RADIUS * (np.cos(turns) * rotation[0] + np.sin(turns) * rotation[1])
    return float(cv2.contourArea(calibration.project(outline).astype(np.float32)))


def recall(run_dir: Path | None) -> JointFit | None:
    """The offsets measured earlier in this run, or None."""
    path = None if run_dir is None else Path(run_dir) / OFFSETS
    if path is None or not path.is_file():
        return None
    try:
        return JointFit.from_json(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError):
        raise UserError(f"{path}: cannot read the arm's measured joints; delete it to measure them again") from None


def keep(run_dir: Path | None, fitted: JointFit) -> None:
    if run_dir is None:
        return
    path = Path(run_dir) / OFFSETS
    temporary = path.with_suffix(".tmp")
    temporary.write_text(json.dumps(fitted.to_json(), indent=1) + "\n", encoding="utf-8")
    temporary.replace(path)
