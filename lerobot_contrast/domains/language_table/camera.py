"""The Language-Table camera as a pinhole model: its pose, world -> camera coordinates and world -> pixel projection.

Pixel coordinates are continuous (col, row) with (0, 0) at the image's top-left corner, as in the benchmark spec.
"""

from __future__ import annotations

import math

import numpy as np

from lerobot_contrast.domains.language_table import board


def euler_xyz_matrix(rx: float, ry: float, rz: float) -> np.ndarray:
    """Rotation of extrinsic x, then y, then z turns (pybullet getQuaternionFromEuler, scipy 'xyz')."""
    cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    rot_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rot_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rot_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rot_z @ rot_y @ rot_x


class Camera:
    """Pose and intrinsics of the benchmark camera (defaults: board.CAMERA_*), sized for a height x width image."""

    def __init__(self, height: int = board.IMAGE_HEIGHT, width: int = board.IMAGE_WIDTH) -> None:
        self.height, self.width = height, width
        self.eye = np.array(board.CAMERA_POSITION, dtype=float)
        rotation = euler_xyz_matrix(*board.CAMERA_EULER_XYZ)
        look = rotation @ (0.0, 0.0, 1.0)
        up_hint = rotation @ (0.0, -1.0, 0.0)
        # Same basis as pybullet's computeViewMatrix(eye, eye + look, up): right, true up, forward.
        right = np.cross(look, up_hint)
        right /= np.linalg.norm(right)
        up = np.cross(right, look)
        self.basis = np.stack([right, up, look])
        self.focal = board.CAMERA_FOCAL_FRACTION * width
        self.center = (width / 2.0, height / 2.0)

    def to_camera(self, points_xyz: np.ndarray) -> np.ndarray:
        """World points (N, 3) -> camera coordinates (N, 3): (right, up, depth along the optical axis)."""
        return (np.asarray(points_xyz, dtype=float) - self.eye) @ self.basis.T

    def project(self, points_xyz: np.ndarray) -> np.ndarray:
        """World points (N, 3) -> pixel coordinates (N, 2) as (col, row); points must lie in front of the camera."""
        cam = self.to_camera(points_xyz)
        return self.project_camera(cam)

    def project_camera(self, cam: np.ndarray) -> np.ndarray:
        """Camera coordinates (N, 3) from `to_camera` -> pixel coordinates (N, 2) as (col, row)."""
        scale = self.focal / cam[:, 2]
        return np.stack([self.center[0] + cam[:, 0] * scale, self.center[1] - cam[:, 1] * scale], axis=1)

    def pixel_rays(self) -> np.ndarray:
        """World-frame direction (H, W, 3) of the ray through each pixel centre (not normalised)."""
        cols = (np.arange(self.width) + 0.5 - self.center[0]) / self.focal
        rows = (np.arange(self.height) + 0.5 - self.center[1]) / self.focal
        right, up, look = self.basis
        return look + cols[None, :, None] * right - rows[:, None, None] * up
