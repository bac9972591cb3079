"""The arm's joint offsets, measured by the camera: a purple ball on the back of the fixed jaw, the jaws moved through
poses over the workspace, and each joint's calibration offset (with where the ball really sits) fitted so that the
arm's model puts the ball where the calibrated camera sees it.

A joint calibrated a few degrees off the arm's model moves the jaws centimetres from where the model puts them: 3
degrees at every joint of the twin (`--joint_offset_deg=3`) brought them down 1.6-2.6 cm short and 1.2-3.6 cm low
across the workspace, and most picks pushed the cube. The five arm joints' offsets and the ball's three coordinates
are eight numbers; a dozen views give two dozen pixel coordinates."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.optimize import least_squares

from lerobot_contrast.so101 import reach

COLOUR = "purple"  # a hue no shipped task's objects have (staging/locate.py's band)
RADIUS = 0.01  # m: a 2 cm ball
# Where the ball sits (the jaws' site frame, m): 3 cm up the fixed jaw from its tip, 2 cm out from its outer face,
# where a camera in front of the arm sees it in most poses that point the jaws down.
AT = (-0.03, 0.0, -0.02)
BODY = "gripper"
# The jaws' calibration poses: the point between them over a grid of the workspace at two heights (clear of cubes
# however far the joints are off), the wrist rolled to show the ball to the camera.
GRID_X, GRID_Y, HEIGHTS = (0.20, 0.27, 0.34, 0.41), (-0.18, -0.06, 0.06, 0.18), (0.10, 0.18)
ROLLS = np.linspace(-1.2, 1.2, 9)  # rad added to the wrist roll the IK chose, the one facing the camera best taken
PLACE_PRIOR_M = 0.005  # how far the ball may sit from AT, as a user sticks it on (one standard deviation)
LOSS_SCALE_PX = 2.0  # residuals beyond this are down-weighted: a ball partly hidden by the arm shifts its centroid


@dataclass(frozen=True)
class JointFit:
    """Each arm joint's offset (radians: its true angle is its reading plus this), where the ball sits (site frame),
    the fit's RMS error in pixels, and how many views it used."""

    offsets: Mapping[str, float]
    at: tuple[float, float, float]
    error_px: float
    views: int

    def to_json(self) -> dict:
        return {"offsets_deg": {name: round(math.degrees(value), 4) for name, value in self.offsets.items()},
                "ball_at_m": [round(v, 5) for v in self.at], "error_px": round(self.error_px, 3), "views": self.views}  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping) -> JointFit:
        offsets = {name: math.radians(float(data["offsets_deg"][name])) for name in reach.ARM_JOINTS}
        at = tuple(float(v) for v in data["ball_at_m"])
        return cls(offsets, (at[0], at[1], at[2]), float(data["error_px"]), int(data["views"]))


def add_ball(spec: mujoco.MjSpec, rgba: Sequence[float]) -> None:
    """The ball on the fixed jaw, seen by the camera and touching nothing (no contacts, no mass to speak of)."""
    site = spec.site(reach.SITE)
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.asarray(site.quat, np.float64))
    ball = spec.body(BODY).add_geom()
    ball.name, ball.type, ball.size = "jaw_ball", mujoco.mjtGeom.mjGEOM_SPHERE, [RADIUS, 0.0, 0.0]
    ball.pos = np.asarray(site.pos) + rotation.reshape(3, 3) @ np.asarray(AT)
    ball.rgba, ball.contype, ball.conaffinity, ball.mass = list(rgba), 0, 0, 1e-4


def poses(model: mujoco.MjModel, rest: Mapping[str, float], camera: np.ndarray) -> list[dict[str, float]]:
    """The arm joints' goals of each calibration view, the wrist rolled to turn the ball towards the `camera` (its
    position, m), in an order that keeps each move short (a serpentine over the grid). Points the arm cannot reach
    pointing down are left out."""
    data = mujoco.MjData(model)
    found = []
    for row, x in enumerate(GRID_X):
        ys = GRID_Y if row % 2 == 0 else GRID_Y[::-1]
        for y, height in itertools.product(ys, HEIGHTS):
            try:
                joints = reach.solve(model, np.zeros(3), np.array([x, y, height]), None, rest)
            except reach.Unreachable:
                continue
            rolled = ({**joints, "wrist_roll": joints["wrist_roll"] + roll} for roll in ROLLS)
            found.append(max(rolled, key=lambda pose: _facing(model, data, pose, camera)))
    return found


def _facing(model: mujoco.MjModel, data: mujoco.MjData, joints: Mapping[str, float], camera: np.ndarray) -> float:
    """How squarely the ball's outer side faces the camera (the cosine between them): the ball sits out from the
    fixed jaw's outer face, along the site's -z axis, and the jaw hides it from a camera on the other side."""
    ball = ball_position(model, data, joints, AT)
    outward = -data.site(reach.SITE).xmat.reshape(3, 3)[:, 2]
    towards = camera - ball
    return float(outward @ towards / np.linalg.norm(towards))


def ball_position(model: mujoco.MjModel, data: mujoco.MjData, joints: Mapping[str, float], at) -> np.ndarray:
    """Where the ball sits in the world (m) with the arm's joints at `joints` (true angles)."""
    for name in reach.ARM_JOINTS:
        data.qpos[model.joint(name).qposadr[0]] = joints[name]
    mujoco.mj_kinematics(model, data)
    site = data.site(reach.SITE)
    return site.xpos + site.xmat.reshape(3, 3) @ np.asarray(at, np.float64)


def fit(model: mujoco.MjModel, project, readings: Sequence[Mapping[str, float]], pixels: np.ndarray) -> JointFit:
    """The offsets and ball place that best explain the ball's `pixels` (N, 2) seen with the joints read as
    `readings`; `project` maps world points (N, 3) to pixels (the calibrated camera)."""
    data = mujoco.MjData(model)
    names = reach.ARM_JOINTS

    def ball_pixels(params: np.ndarray) -> np.ndarray:
        offsets, at = params[: len(names)], params[len(names) :]
        points = [ball_position(model, data, {n: r[n] + o for n, o in zip(names, offsets, strict=True)}, at)
                  for r in readings]  # fmt: skip
        return project(np.array(points))

    def residuals(params: np.ndarray) -> np.ndarray:
        prior = (params[len(names) :] - np.asarray(AT)) / PLACE_PRIOR_M
        return np.concatenate([(ball_pixels(params) - pixels).ravel(), prior])

    start = np.concatenate([np.zeros(len(names)), AT])
    result = least_squares(residuals, start, loss="soft_l1", f_scale=LOSS_SCALE_PX, x_scale=0.01)
    error = float(np.sqrt(np.mean(np.sum((ball_pixels(result.x) - pixels) ** 2, axis=1))))
    offsets = {name: float(value) for name, value in zip(names, result.x[: len(names)], strict=True)}
    at = tuple(float(v) for v in result.x[len(names) :])
    return JointFit(offsets, (at[0], at[1], at[2]), error, len(readings))
