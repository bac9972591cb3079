"""The camera's lens (a wide-angle webcam's bends straight lines): OpenCV's radial model fitted from the board's
marker corners in one view, and how far its uncertainty moves points across the workspace.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np

ITERATIONS = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)  # undistorting far from the centre
# One view of a board fixes the principal point poorly and tangential terms not at all: only focal length and k1 are
# fitted. k2 trades off against k1 over a board that covers part of the frame, and is left at 0.
FLAGS = (
    cv2.CALIB_USE_INTRINSIC_GUESS
    | cv2.CALIB_FIX_PRINCIPAL_POINT
    | cv2.CALIB_FIX_ASPECT_RATIO
    | cv2.CALIB_ZERO_TANGENT_DIST
    | cv2.CALIB_FIX_K2
    | cv2.CALIB_FIX_K3
)
SIGMAS = 3.0  # the lens's spread is judged at k1 +- 3 standard deviations
FALLBACK_FOCAL_FRACTION = 0.8  # of the image's width: a typical webcam's, where one view cannot tell it
MAX_FOCAL_SIGMA = 0.1  # relative: a focal length less sure than this is not used (then the fallback is)


@dataclass(frozen=True)
class Lens:
    """OpenCV's model: a ray (x, y, 1) shows at focal * (x, y) * (1 + k1 r^2 + k2 r^4) + centre, r^2 = x^2 + y^2;
    a lens-free camera would show it at focal * (x, y) + centre (its ideal pixel)."""

    focal: float
    centre: tuple[float, float]
    k1: float
    k2: float = 0.0
    k1_sigma: float = 0.0  # the fit's standard deviation of k1

    @property
    def matrix(self) -> np.ndarray:
        return np.array([[self.focal, 0, self.centre[0]], [0, self.focal, self.centre[1]], [0, 0, 1]])

    @property
    def coefficients(self) -> np.ndarray:
        return np.array([self.k1, self.k2, 0.0, 0.0, 0.0])

    def undistort(self, pixels: np.ndarray) -> np.ndarray:
        """Pixels (N, 2) seen through the lens -> where a lens-free camera with the same focal length sees them."""
        points = np.asarray(pixels, np.float64).reshape(-1, 1, 2)
        if len(points) == 0:
            return points.reshape(0, 2)
        return cv2.undistortPointsIter(points, self.matrix, self.coefficients, None, self.matrix, ITERATIONS).reshape(
            -1, 2
        )

    def distort(self, ideal: np.ndarray) -> np.ndarray:
        """The inverse of `undistort`."""
        ideal = np.asarray(ideal, np.float64).reshape(-1, 2)
        rays = np.column_stack([(ideal - self.centre) / self.focal, np.ones(len(ideal))])
        if len(rays) == 0:
            return ideal
        pixels, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), self.matrix, self.coefficients)
        return pixels.reshape(-1, 2)

    def to_json(self) -> dict[str, Any]:
        return {
            "model": "opencv_radial",
            "focal_px": round(self.focal, 3),
            "centre_px": [round(c, 3) for c in self.centre],
            "k1": round(self.k1, 6),
            "k2": round(self.k2, 6),
            "k1_sigma": round(self.k1_sigma, 6),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Lens:
        if data["model"] != "opencv_radial":
            raise ValueError(f"unknown lens model {data['model']!r}")
        centre = tuple(float(c) for c in data["centre_px"])
        return cls(float(data["focal_px"]), centre, float(data["k1"]), float(data["k2"]), float(data["k1_sigma"]))


def fit_lens(table: np.ndarray, pixels: np.ndarray, image_size: tuple[int, int], focal: float | None) -> Lens:
    """The lens that sends the board's points on the table (N, 2) to where they were seen (N, 2); `focal` is the
    guess (None where one view cannot tell it, looking nearly straight down: then it stays at a typical webcam's)."""
    width, height = image_size
    centre = ((width - 1) / 2, (height - 1) / 2)
    fallback = Lens(FALLBACK_FOCAL_FRACTION * width, centre, 0.0)
    fitted, focal_sigma = _calibrate(table, pixels, image_size, Lens(focal or fallback.focal, centre, 0.0), not focal)
    if focal_sigma > MAX_FOCAL_SIGMA * fitted.focal:  # the view does not tell the focal length after all
        fitted, _ = _calibrate(table, pixels, image_size, fallback, fixed_focal=True)
    return fitted


def _calibrate(
    table: np.ndarray, pixels: np.ndarray, size: tuple[int, int], guess: Lens, fixed_focal: bool
) -> tuple[Lens, float]:
    """The lens fitted from `guess`, and the standard deviation of its focal length (0 when fixed)."""
    objects = np.column_stack([table, np.zeros(len(table))]).astype(np.float32)
    flags = FLAGS | (cv2.CALIB_FIX_FOCAL_LENGTH if fixed_focal else 0)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    _, matrix, coefficients, *_, deviations, _, _ = cv2.calibrateCameraExtended(
        [objects], [pixels.astype(np.float32)], size, guess.matrix, guess.coefficients, flags=flags, criteria=criteria
    )
    # With the aspect ratio fixed OpenCV fits fy and derives fx: the focal length's deviation is fy's.
    focal_sigma, sigma = (float(d) if np.isfinite(d) else math.inf for d in deviations.ravel()[[1, 4]])
    k1 = float(coefficients.ravel()[0])
    return Lens(float(matrix[0, 0]), guess.centre, k1, 0.0, min(sigma, 1.0)), focal_sigma


def spread_m(table: np.ndarray, pixels: np.ndarray, lens: Lens, workspace: np.ndarray) -> float:
    """How far (metres) the `workspace` points (M, 2) on the table move when k1 is `SIGMAS` standard deviations off
    and the homography is refitted to the board: what the lens's uncertainty costs where the board is not."""
    ideal = cv2.findHomography(table, lens.undistort(pixels), 0)[0]
    seen = lens.distort(cv2.perspectiveTransform(workspace.reshape(-1, 1, 2), ideal).reshape(-1, 2))
    worst = 0.0
    for sign in (-1.0, 1.0):
        other = replace(lens, k1=lens.k1 + sign * SIGMAS * lens.k1_sigma)
        homography = cv2.findHomography(table, other.undistort(pixels), 0)[0]
        back = cv2.perspectiveTransform(other.undistort(seen).reshape(-1, 1, 2), np.linalg.inv(homography))
        worst = max(worst, float(np.max(np.linalg.norm(back.reshape(-1, 2) - workspace, axis=1))))
    return worst
