"""Find coloured objects in a camera frame and place them on the table through the calibration.

Each colour is a hue band (OpenCV HSV, hue 0-179) of saturated, lit pixels inside the workspace; an object is the
largest such blob, placed where the ray through its centroid meets the plane halfway up the object.
"""

from __future__ import annotations

from collections.abc import Mapping

import cv2
import numpy as np

from lerobot_contrast.staging.homography import CameraCalibration

HUES = {
    "red": ((0, 8), (170, 180)),
    "orange": ((9, 19),),
    "yellow": ((20, 35),),
    "green": ((36, 85),),
    "blue": ((95, 130),),
    "purple": ((131, 160),),
}
MIN_SATURATION, MIN_VALUE = 80, 60
MIN_PIXELS = 12  # smaller blobs are noise, or an object mostly hidden (by the arm): better not found than wrong
# A blob counts as the object when its area is within these multiples of the object's footprint seen from the camera
# (its top and sides show too); anything else is clutter of the same colour, or the object mostly hidden.
AREA_RANGE = (0.25, 6.0)
OUTLINE_POINTS = 16  # per edge of the workspace's outline


def workspace_mask(
    calibration: CameraCalibration, bounds: tuple[tuple[float, float], tuple[float, float]], height: float = 0.0
) -> np.ndarray:
    """Pixels whose table point lies inside `bounds` ((x_min, y_min), (x_max, y_max)), as a uint8 mask; with
    `height`, also those where objects that tall standing inside it show (their tops reach past its far edge)."""
    (x0, y0), (x1, y1) = bounds
    # Each edge sampled along its length: through a wide-angle lens the workspace's straight edges are curves.
    along = np.linspace(0, 1, OUTLINE_POINTS, endpoint=False)[:, None]
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    outline = np.concatenate([a + along * (b - a) for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True)])
    width, image_height = calibration.image_size
    mask = np.zeros((image_height, width), np.uint8)
    cv2.fillPoly(mask, [np.round(calibration.to_pixels(outline)).astype(np.int32)], 255)
    if height > 0:
        raised = np.concatenate([calibration.to_pixels(outline), calibration.lift(outline, height)])
        cv2.fillPoly(mask, [cv2.convexHull(np.round(raised).astype(np.int32))], 255)
    return mask


def colour_mask(image: np.ndarray, colour: str) -> np.ndarray:
    hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)
    mask = np.zeros(image.shape[:2], np.uint8)
    for low, high in HUES[colour]:
        mask |= cv2.inRange(hsv, (low, MIN_SATURATION, MIN_VALUE), (min(high, 179), 255, 255))
    return mask


def find_objects(
    image: np.ndarray,
    calibration: CameraCalibration,
    colours: Mapping[str, str],
    bounds: tuple[tuple[float, float], tuple[float, float]],
    height: float,
) -> dict[str, tuple[float, float]]:
    """Table (x, y) of each object in `colours` ({name: colour}) seen in the RGB `image`; unseen ones are left out.
    The object is the largest blob of its colour standing on the workspace, seen with the part of it that shows past
    the workspace's far edge (a tall object's top), or, where that merges it with something beyond the edge, without."""
    regions = (workspace_mask(calibration, bounds, height), workspace_mask(calibration, bounds))
    found: dict[str, tuple[float, float]] = {}
    for name, colour in colours.items():
        seen = colour_mask(image, colour)
        for region in regions:
            place = _blob_place(seen & region, bounds, calibration, height)
            if place is not None:
                found[name] = place
                break
    return found


def _blob_place(
    mask: np.ndarray,
    bounds: tuple[tuple[float, float], tuple[float, float]],
    calibration: CameraCalibration,
    height: float,
) -> tuple[float, float] | None:
    """Where the largest blob in `mask` standing on the workspace stands, if its size is an object's. A blob stands
    on it where its centre does: an object seen from a low camera near the workspace's far edge shows most of its
    pixels past that edge (its top and the face towards the camera), one beyond the edge its centre past it."""
    count, _, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    places = calibration.to_table(centroids[1:], height / 2) if count > 1 else np.zeros((0, 2))
    (x0, y0), (x1, y1) = bounds
    standing = [i for i in range(1, count) if x0 <= places[i - 1][0] <= x1 and y0 <= places[i - 1][1] <= y1]
    if not standing:
        return None
    best = max(standing, key=lambda i: stats[i, cv2.CC_STAT_AREA])
    area = stats[best, cv2.CC_STAT_AREA]
    x, y = places[best - 1]
    expected = _footprint_pixels(calibration, x, y, height)
    if area >= MIN_PIXELS and AREA_RANGE[0] * expected <= area <= AREA_RANGE[1] * expected:
        return float(x), float(y)
    return None


def _footprint_pixels(calibration: CameraCalibration, x: float, y: float, size: float) -> float:
    """Pixel area of a square of side `size` lying on the table at (x, y)."""
    half = size / 2
    square = np.array([[x - half, y - half], [x + half, y - half], [x + half, y + half], [x - half, y + half]])
    return float(cv2.contourArea(calibration.to_pixels(square).astype(np.float32)))


def known_colour(value: str | None) -> str | None:
    """The hue band a task's colour word names (colour or color, any case), None where there is none."""
    word = (value or "").strip().lower()
    return word if word in HUES else None


def blob_near(
    image: np.ndarray, colour: str, near: np.ndarray, within_px: float, min_pixels: float
) -> np.ndarray | None:
    """The centroid (col, row) of the blob of `colour` nearest pixel `near`, if it lies within `within_px` of it and
    has at least `min_pixels`: where a marker of that colour is seen whole, where it is expected to be."""
    count, _, stats, centroids = cv2.connectedComponentsWithStats(colour_mask(image, colour), connectivity=8)
    blobs = [i for i in range(1, count) if stats[i, cv2.CC_STAT_AREA] >= MIN_PIXELS]  # specks are noise
    if not blobs:
        return None
    best = min(blobs, key=lambda i: np.hypot(*(centroids[i] - near)))
    whole = stats[best, cv2.CC_STAT_AREA] >= min_pixels
    return centroids[best] if whole and np.hypot(*(centroids[best] - near)) <= within_px else None
