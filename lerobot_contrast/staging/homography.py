"""The table-to-camera calibration: the lens and the homography fitted to the board's markers, its JSON file, and
mapping between table metres and pixels, including points above the table (an object's centre) through the camera
pose it implies. Pixels follow OpenCV: (col, row) with pixel centres at integers.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.staging import board
from lerobot_contrast.staging.lens import FALLBACK_FOCAL_FRACTION, Lens, fit_lens, spread_m

CALIBRATION_VERSION = 2  # 2: the lens; files of version 1 (a homography alone) still load, as a lens-free camera
READABLE_VERSIONS = (1, 2)
MIN_MARKERS = 4  # fewer leaves the fit unchecked (one marker's four corners fit any homography exactly)
# Nearer square on than this (the camera's axis to the table's normal), one view cannot tell the focal length.
MIN_TILT_DEG = 5.0
# The most the lens's uncertainty (k1 +- 3 standard deviations) may move a point of the workspace: half the 2 cm
# staging tolerance, so that a cube placed right is never flagged for the lens alone.
MAX_SPREAD_M = 0.01


class CalibrationError(UserError):
    pass


@dataclass(frozen=True)
class CameraCalibration:
    """One camera's view of the table plane."""

    camera: str
    image_size: tuple[int, int]  # width, height
    homography: np.ndarray  # (3, 3): table (x, y, 1) in metres -> pixel (col, row, 1)
    error_px: float  # RMS reprojection error of the marker corners
    markers: int
    lens: Lens | None = None  # None: a lens-free (pinhole) camera; the homography maps to undistorted pixels

    def to_pixels(self, xy: np.ndarray) -> np.ndarray:
        """Table points (N, 2) on the table's surface -> pixels (N, 2), as the camera sees them (through its lens)."""
        ideal = cv2.perspectiveTransform(np.asarray(xy, np.float64).reshape(-1, 1, 2), self.homography).reshape(-1, 2)
        return ideal if self.lens is None else self.lens.distort(ideal)

    def to_table(self, pixels: np.ndarray, height: float = 0.0) -> np.ndarray:
        """Pixels (N, 2) -> table points (N, 2) where their rays cross the plane `height` metres above the table."""
        pixels = np.asarray(pixels, np.float64).reshape(-1, 2)
        if self.lens is not None:
            pixels = self.lens.undistort(pixels)
        if height == 0.0:
            inverse = np.linalg.inv(self.homography)
            return cv2.perspectiveTransform(pixels.reshape(-1, 1, 2), inverse).reshape(-1, 2)
        centre, rays = self._rays(pixels)
        scale = (height - centre[2]) / rays[:, 2]
        return centre[:2] + scale[:, None] * rays[:, :2]

    def lift(self, xy: np.ndarray, height: float) -> np.ndarray:
        """Table points (N, 2) raised `height` metres -> pixels (N, 2)."""
        return self.project(np.column_stack([np.asarray(xy, np.float64).reshape(-1, 2), np.full(len(xy), height)]))

    def project(self, points: np.ndarray) -> np.ndarray:
        """Points (N, 3) in the table's frame (x, y on it, z up from it, metres) -> pixels (N, 2)."""
        intrinsics, rotation, translation = self.pose()
        camera = np.asarray(points, np.float64).reshape(-1, 3) @ rotation.T + translation
        projected = camera @ intrinsics.T
        ideal = projected[:, :2] / projected[:, 2:]
        return ideal if self.lens is None else self.lens.distort(ideal)

    def pose(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Intrinsics, rotation and translation (table -> camera) implied by the homography, for square pixels
        centred on the image (the lens's focal length where it was fitted)."""
        width, height = self.image_size
        focal = self.lens.focal if self.lens is not None else None
        focal = focal or _focal(self.homography, (width - 1) / 2, (height - 1) / 2) or FALLBACK_FOCAL_FRACTION * width
        intrinsics = np.array([[focal, 0, (width - 1) / 2], [0, focal, (height - 1) / 2], [0, 0, 1]])
        columns = np.linalg.inv(intrinsics) @ self.homography
        scale = 1.0 / np.linalg.norm(columns[:, 0])
        if columns[2, 2] * scale < 0:  # the table lies in front of the camera
            scale = -scale
        r1, r2, translation = (columns * scale).T
        u, _, vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
        return intrinsics, u @ vt, translation

    def _rays(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        intrinsics, rotation, translation = self.pose()
        centre = -rotation.T @ translation
        homogeneous = np.column_stack([pixels, np.ones(len(pixels))])
        return centre, homogeneous @ np.linalg.inv(intrinsics).T @ rotation

    def to_json(self) -> dict[str, Any]:
        return {
            "camera": self.camera,
            "image_size": list(self.image_size),
            "homography": self.homography.tolist(),
            "error_px": round(self.error_px, 4),
            "markers": self.markers,
            "lens": None if self.lens is None else self.lens.to_json(),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> CameraCalibration:
        lens = data.get("lens")
        return cls(
            data["camera"], tuple(data["image_size"]), np.array(data["homography"], float), data["error_px"],
            data["markers"], None if lens is None else Lens.from_json(lens),
        )  # fmt: skip


def _focal(homography: np.ndarray, cx: float, cy: float) -> float | None:
    """The focal length (pixels) that makes the homography's two table axes orthogonal and of equal length
    (Zhang's constraints, least squares); None where the view cannot tell it (looking straight down)."""
    h = np.array([[1, 0, -cx], [0, 1, -cy], [0, 0, 1]]) @ homography
    a = np.array([h[0, 0] * h[0, 1] + h[1, 0] * h[1, 1], h[0, 0] ** 2 + h[1, 0] ** 2 - h[0, 1] ** 2 - h[1, 1] ** 2])
    b = np.array([h[2, 0] * h[2, 1], h[2, 0] ** 2 - h[2, 1] ** 2])
    inverse_square = -(a @ b) / (a @ a)
    if not math.isfinite(inverse_square) or inverse_square <= 0 or abs(a @ b) < 1e-12 * np.linalg.norm(a) ** 2:
        return None
    return 1.0 / math.sqrt(inverse_square)


def _focal_guess(calibration: CameraCalibration) -> float | None:
    """The focal length the homography implies, None where the view is too nearly square on to tell it."""
    _, rotation, _ = calibration.pose()
    if math.degrees(math.acos(min(1.0, abs(rotation[2, 2])))) < MIN_TILT_DEG:
        return None
    width, height = calibration.image_size
    return _focal(calibration.homography, (width - 1) / 2, (height - 1) / 2)


def detect_board(image: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Board-frame points (N, 2) and their pixels (N, 2) for every marker corner found, and how many markers."""
    grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_APRILTAG
    corners, ids, _ = cv2.aruco.ArucoDetector(board.dictionary(), parameters).detectMarkers(grey)
    if ids is None or len(ids) == 0:
        return np.empty((0, 2)), np.empty((0, 2)), 0
    objects, pixels = board.grid_board().matchImagePoints(corners, ids)
    return objects.reshape(-1, 3)[:, :2], pixels.reshape(-1, 2).astype(np.float64), len(ids)


Bounds = tuple[tuple[float, float], tuple[float, float]]


def fit(
    camera: str, image: np.ndarray, where: board.BoardArgs, max_error_px: float, workspace: Bounds,
    lens: bool = True,
) -> CameraCalibration:  # fmt: skip
    """The lens and homography from the board found in `image`, lying on the table as `where` says (`lens=False`:
    the homography alone); one-line errors when the board is not found, the fit is worse than `max_error_px`, or
    the lens is too uncertain over the `workspace` ((x_min, y_min), (x_max, y_max)) to trust."""
    objects, pixels, markers = detect_board(image)
    if markers < MIN_MARKERS:
        seen = "no marker" if markers == 0 else f"only {markers} of {board.COLUMNS * board.ROWS} markers"
        raise CalibrationError(
            f"camera {camera}: board not found ({seen} of the printed ArUco board in view); lay the whole board flat "
            "in the camera's view, well lit, and try again"
        )
    table = board.board_to_table(objects, where)
    size = (image.shape[1], image.shape[0])
    fitted = None
    if lens:
        plain = CameraCalibration(camera, size, cv2.findHomography(table, pixels, 0)[0], 0.0, markers)
        try:
            fitted = fit_lens(table, pixels, size, _focal_guess(plain))
        except cv2.error:
            raise CalibrationError(
                f"camera {camera}: the markers seen cannot measure the lens; lay the whole board flat in view"
            ) from None
    homography = cv2.findHomography(table, pixels if fitted is None else fitted.undistort(pixels), 0)[0]
    calibration = CameraCalibration(camera, size, homography, 0.0, markers, fitted)
    error = float(np.sqrt(np.mean(np.sum((calibration.to_pixels(table) - pixels) ** 2, axis=1))))
    if error > max_error_px:
        raise CalibrationError(
            f"camera {camera}: reprojection error {error:.2f} px is above --max_error_px={max_error_px:g}; the board "
            "is not flat, or is printed scaled (print at 100%), or the camera moved: flatten it and try again"
        )
    if fitted is not None:
        _check_spread(calibration, table, pixels, workspace)
    return replace(calibration, error_px=error)


def _check_spread(calibration: CameraCalibration, table: np.ndarray, pixels: np.ndarray, workspace: Bounds) -> None:
    """Refuse a lens the board pins too loosely for the workspace's points in view."""
    (x0, y0), (x1, y1) = workspace
    grid = np.array([[x, y] for x in np.linspace(x0, x1, 7) for y in np.linspace(y0, y1, 9)])
    seen = calibration.to_pixels(grid)
    width, height = calibration.image_size
    # A homography also maps points behind the camera into the frame: those are on the other side from the board's.
    depth = np.column_stack([np.vstack([grid, table[:1]]), np.ones(len(grid) + 1)]) @ calibration.homography[2]
    ahead = np.sign(depth[:-1]) == np.sign(depth[-1])
    inside = ahead & np.all((seen >= 0) & (seen <= (width - 1, height - 1)), axis=1)
    if not inside.any():
        raise CalibrationError(
            f"camera {calibration.camera}: the task's workspace is not in view; aim the camera at the table"
        )
    spread = spread_m(table, pixels, calibration.lens, grid[inside])
    if spread > MAX_SPREAD_M:
        raise CalibrationError(
            f"camera {calibration.camera}: the board covers too little of the view to measure the lens (up to "
            f"{spread * 100:.1f} cm uncertain at the workspace's edge); lay it nearer the image's edge, or nearer the "
            "camera, and give its new --board.x/--board.y"
        )


def save(path: Path, calibrations: list[CameraCalibration], where: board.BoardArgs) -> None:
    data = {
        "version": CALIBRATION_VERSION,
        "board": {"x": where.x, "y": where.y, "yaw_deg": where.yaw_deg, "printed": board.printed_size_text()},
        "cameras": {c.camera: c.to_json() for c in calibrations},
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_suffix(".tmp")
    temporary.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    temporary.replace(path)


def load(path: Path) -> dict[str, CameraCalibration]:
    """The calibrated cameras in `path`; a missing or damaged file is one line saying how to make it."""
    redo = "run python -m lerobot_contrast.calibrate with the task's --task and your --robot flags"
    if not path.is_file():
        raise CalibrationError(f"{path}: no table calibration; {redo}")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if data.get("version") not in READABLE_VERSIONS:
            raise CalibrationError(f"{path}: calibration version {data.get('version')!r}, expected "
                                   f"{CALIBRATION_VERSION}; {redo}")  # fmt: skip
        return {name: CameraCalibration.from_json(item) for name, item in data["cameras"].items()}
    except (json.JSONDecodeError, KeyError, TypeError, ValueError):
        raise CalibrationError(f"{path}: not a table calibration file; {redo}") from None
