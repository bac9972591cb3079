"""The twin camera's lens and sensor: OpenCV's radial and tangential distortion applied to an ideal pinhole render,
uneven light (vignetting and a light gradient) and seeded sensor noise, so a frame looks like a USB webcam's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from lerobot_contrast.contrast.errors import UserError

NOISE_SHIFT = 64  # the noise bank is this many pixels larger than a frame each way; each frame takes a shifted window
# Where the radial map's slope falls below this the lens nearly folds the image over itself: refused.
MIN_SLOPE = 0.2


class LensError(UserError):
    pass


@dataclass(frozen=True)
class LensArgs:
    """The webcam's lens and sensor, in OpenCV's camera model (the k1 that cv2.undistortPoints inverts)."""

    # Radial distortion: k1 < 0 is barrel (a wide-angle webcam), 0 a perfect pinhole.
    k1: float = -0.3
    k2: float = 0.0
    # Tangential distortion (a lens mounted slightly tilted).
    p1: float = 0.0
    p2: float = 0.0
    # Brightness lost at the image's corners (0: none, 0.3: a typical webcam).
    vignetting: float = 0.3
    # Brightness difference across the frame, from the lit side to the far side (0: even light).
    gradient: float = 0.25
    # Where the light comes from in the image, degrees (0: from the left, 90: from the top).
    gradient_deg: float = 30.0
    # Sensor noise: standard deviation in 8-bit grey levels.
    noise: float = 2.0
    # Seed of the sensor noise.
    seed: int = 0

    def coefficients(self) -> np.ndarray:
        """OpenCV's distortion vector (k1, k2, p1, p2)."""
        return np.array([self.k1, self.k2, self.p1, self.p2], np.float64)


class Lens:
    """Turns an ideal render into the webcam's frame. The render (the canvas) is a pinhole image with the same focal
    length, larger than the frame so that every frame pixel's ray falls inside it; `canvas_size` says how large."""

    def __init__(self, args: LensArgs, focal_px: float, size: tuple[int, int]) -> None:
        self.args, self.size = args, size
        width, height = size
        self.intrinsics = np.array([[focal_px, 0, (width - 1) / 2], [0, focal_px, (height - 1) / 2], [0, 0, 1]])
        rays = _frame_rays(self.intrinsics, args, size)
        half = np.abs(rays).reshape(-1, 2).max(axis=0) * focal_px
        # Two pixels beyond the farthest ray each way, so bilinear sampling never reads past the canvas.
        self.canvas_size = (int(math.ceil(2 * half[0])) + 5, int(math.ceil(2 * half[1])) + 5)
        canvas_centre = (np.array(self.canvas_size) - 1) / 2
        pixels = (rays * focal_px + canvas_centre).astype(np.float32)
        self._map1, self._map2 = cv2.convertMaps(pixels[..., 0], pixels[..., 1], cv2.CV_16SC2)
        self._gain = _light(args, size)
        self._rng = np.random.default_rng(args.seed)
        bank = self._rng.standard_normal((height + NOISE_SHIFT, width + NOISE_SHIFT, 3), dtype=np.float32)
        self._noise = np.round(bank * args.noise).astype(np.int16)

    def canvas_fovy_deg(self) -> float:
        """The vertical field of view of the canvas a renderer must draw (square pixels, centred)."""
        return math.degrees(2 * math.atan(self.canvas_size[1] / 2 / self.intrinsics[0, 0]))

    def apply(self, canvas: np.ndarray) -> np.ndarray:
        """The frame the webcam gives for an ideal render of `canvas_size` (RGB, uint8)."""
        if canvas.shape[1::-1] != self.canvas_size:
            width, height = self.canvas_size
            raise ValueError(f"the render is {canvas.shape[1]}x{canvas.shape[0]}, the lens needs {width}x{height}")
        frame = cv2.remap(canvas, self._map1, self._map2, cv2.INTER_LINEAR)
        gain, scale = self._gain
        frame = cv2.multiply(frame, gain, scale=scale)
        # A fresh normal draw per pixel costs most of a 30 Hz frame; a shifted window of a seeded bank costs 1 ms.
        width, height = self.size
        dy, dx = self._rng.integers(0, NOISE_SHIFT, 2)
        return cv2.add(frame, self._noise[dy : dy + height, dx : dx + width], dtype=cv2.CV_8U)


def _frame_rays(intrinsics: np.ndarray, args: LensArgs, size: tuple[int, int]) -> np.ndarray:
    """For each frame pixel (H, W, 2): the undistorted normalised ray OpenCV's model gives it; a lens that folds
    the frame (no ray, or a ray past the radial map's turning point) is refused in one line."""
    width, height = size
    cols, rows = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    pixels = np.stack([cols, rows], axis=-1)
    # A lens folds the frame first at its edges: check there that the rays found project back onto their pixels.
    edge_pixels = _edges(pixels)
    edge = _undistort(edge_pixels, intrinsics, args)
    back, _ = cv2.projectPoints(np.column_stack([edge, np.ones(len(edge))]), np.zeros(3), np.zeros(3), intrinsics,
                                args.coefficients())  # fmt: skip
    radius = np.linalg.norm(edge, axis=1).max()
    slope = 1 + 3 * args.k1 * radius**2 + 5 * args.k2 * radius**4
    if not np.all(np.isfinite(edge)) or np.abs(back.reshape(-1, 2) - edge_pixels).max() > 0.01 or slope < MIN_SLOPE:
        raise LensError(
            f"lens k1={args.k1:g} k2={args.k2:g} p1={args.p1:g} p2={args.p2:g}: the distortion folds the image before "
            f"its corners at a focal length of {intrinsics[0, 0]:.0f} px; use a weaker lens or a longer focal length"
        )
    return _undistort(pixels.reshape(-1, 2), intrinsics, args).reshape(height, width, 2)


def _undistort(pixels: np.ndarray, intrinsics: np.ndarray, args: LensArgs) -> np.ndarray:
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    rays = cv2.undistortPointsIter(pixels.reshape(-1, 1, 2), intrinsics, args.coefficients(), None, None, criteria)
    return rays.reshape(-1, 2)


def _edges(grid: np.ndarray) -> np.ndarray:
    return np.concatenate([grid[0], grid[-1], grid[:, 0], grid[:, -1]])


def _light(args: LensArgs, size: tuple[int, int]) -> tuple[np.ndarray, float]:
    """The per-pixel gain of vignetting times a directional gradient, as uint8 (3 channels) and its scale."""
    width, height = size
    cols, rows = np.meshgrid(np.arange(width) - (width - 1) / 2, np.arange(height) - (height - 1) / 2)
    vignette = 1 - args.vignetting * (cols**2 + rows**2) / (((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2)
    angle = math.radians(args.gradient_deg)
    along = -(cols * math.cos(angle) + rows * math.sin(angle))  # +1 at the edge the light comes from
    along /= np.abs(along).max()
    gain = vignette * (1 + args.gradient / 2 * along)
    scale = max(float(gain.max()), 1.0) / 255
    quantised = np.clip(np.round(gain / scale), 0, 255).astype(np.uint8)
    return np.repeat(quantised[..., None], 3, axis=2), scale
