"""A synthetic bench camera for tests and benchmarks: a pinhole camera with OpenCV's radial lens model looking at the
table from an oblique pose, photographing the printed board lying on it with uneven light, blur, noise and JPEG.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import cv2
import numpy as np

from lerobot_contrast.staging import board

TABLE_RGB = np.array([150.0, 138.0, 118.0])
CUBE_RGB = {"red": (200, 35, 35), "green": (45, 165, 70), "blue": (40, 80, 205), "yellow": (225, 200, 40)}
CUBE_M = 0.03
SUPERSAMPLE = 2  # rendered at twice the size, then averaged down: the board's edges antialiased as a sensor's are
STRIDE = 8  # (supersampled) pixels between the points where the page's position is computed exactly
ITERATIONS = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)  # undistorting far from the centre


@dataclass(frozen=True)
class ObliqueCamera:
    """A camera at `elevation_deg` above the table and `azimuth_deg` around the point it looks at, as far away as
    lets the `bounds` (the workspace) fill the frame; `k1` is its lens's radial distortion."""

    elevation_deg: float
    azimuth_deg: float
    k1: float = 0.0
    width: int = 640
    height: int = 480
    focal: float = 600.0
    bounds: tuple[tuple[float, float], tuple[float, float]] = ((0.15, -0.25), (0.45, 0.25))
    fill: float = 0.92  # the share of the frame's half-size the workspace's farthest point reaches

    @property
    def matrix(self) -> np.ndarray:
        return np.array([[self.focal, 0, (self.width - 1) / 2], [0, self.focal, (self.height - 1) / 2], [0, 0, 1]])

    @property
    def distortion(self) -> np.ndarray:
        return np.array([self.k1, 0.0, 0.0, 0.0, 0.0])

    @property
    def centre(self) -> np.ndarray:
        """Where the camera is, on the table's frame (metres)."""
        rotation, translation = self.pose()
        return -rotation.T @ translation

    def pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Rotation and translation (table -> camera), the distance bisected until the workspace fills the frame."""
        near, far = 0.1, 5.0
        for _ in range(40):
            middle = (near + far) / 2
            near, far = (middle, far) if self._reach(*self._look(middle)) > self.fill else (near, middle)
        return self._look(far)

    def project(self, points: np.ndarray) -> np.ndarray:
        """Table points (N, 3), metres, -> pixels (N, 2) through the lens."""
        rotation, translation = self.pose()
        rvec, _ = cv2.Rodrigues(rotation)
        pixels, _ = cv2.projectPoints(np.asarray(points, np.float64), rvec, translation, self.matrix, self.distortion)
        return pixels.reshape(-1, 2)

    def table_points(self, pixels: np.ndarray) -> np.ndarray:
        """Pixels (N, 2) -> where their rays meet the table (N, 2); NaN where they miss it."""
        rotation, translation = self.pose()
        ideal = cv2.undistortPointsIter(
            np.asarray(pixels, np.float64).reshape(-1, 1, 2), self.matrix, self.distortion, None, None, ITERATIONS
        ).reshape(-1, 2)
        rays = np.column_stack([ideal, np.ones(len(ideal))]) @ rotation
        centre = -rotation.T @ translation
        scale = -centre[2] / rays[:, 2]
        scale[scale <= 0] = np.nan
        return centre[:2] + scale[:, None] * rays[:, :2]

    def _look(self, distance: float) -> tuple[np.ndarray, np.ndarray]:
        (x0, y0), (x1, y1) = self.bounds
        target = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
        elevation, azimuth = math.radians(self.elevation_deg), math.radians(self.azimuth_deg)
        position = target + distance * np.array(
            [math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth), math.sin(elevation)]
        )
        forward = (target - position) / distance
        right = np.cross(forward, (0.0, 0.0, 1.0))
        right /= np.linalg.norm(right)
        rotation = np.stack([right, np.cross(forward, right), forward])
        return rotation, -rotation @ position

    def _reach(self, rotation: np.ndarray, translation: np.ndarray) -> float:
        """How far the workspace's outline reaches towards the frame's edge (1: on it), before the lens."""
        (x0, y0), (x1, y1) = self.bounds
        edge = np.linspace(0, 1, 9)
        outline = np.concatenate(
            [np.column_stack([x0 + (x1 - x0) * edge, np.full(9, y)]) for y in (y0, y1)]
            + [np.column_stack([np.full(9, x), y0 + (y1 - y0) * edge]) for x in (x0, x1)]
        )
        camera = np.column_stack([outline, np.zeros(len(outline))]) @ rotation.T + translation
        if np.any(camera[:, 2] <= 0):
            return math.inf
        ideal = camera[:, :2] / camera[:, 2:]
        radius = np.sum(ideal**2, axis=1)
        seen = ideal * (1 + self.k1 * radius)[:, None] * self.focal
        return float(np.max(np.abs(seen) / ((self.width - 1) / 2, (self.height - 1) / 2)))


def board_photo(
    camera: ObliqueCamera, where: board.BoardArgs | None, seed: int = 0, quality: int = 85,
    cubes: Mapping[str, tuple[float, float]] | None = None,
) -> np.ndarray:  # fmt: skip
    """An RGB frame of the table, as a webcam gives it, with the printed board lying on it as `where` says (None: no
    board) and `cubes` ({colour: (x, y)}, 3 cm, red, green, blue or yellow) standing on it."""
    size = (camera.width * SUPERSAMPLE, camera.height * SUPERSAMPLE)
    image = np.broadcast_to(TABLE_RGB, (*size[::-1], 3)) if where is None else _paper(camera, where, size)
    image = np.ascontiguousarray(image)
    centre = camera.centre
    for colour, (x, y) in sorted((cubes or {}).items(), key=lambda item: -np.hypot(*(item[1] - centre[:2]))):
        _draw_cube(image, camera, np.array([x, y]), CUBE_RGB[colour])
    image = cv2.resize(image, (camera.width, camera.height), interpolation=cv2.INTER_AREA)
    return _as_webcam(image, np.random.default_rng(seed), quality)


def _draw_cube(image: np.ndarray, camera: ObliqueCamera, xy: np.ndarray, rgb: tuple[int, int, int]) -> None:
    """Paint the faces of a cube standing at `xy` that face the camera (the top lit, the sides shaded)."""
    half = CUBE_M / 2
    along = np.linspace(0, 1, 8, endpoint=False)[:, None]  # edges sampled: the lens bends them
    for axis, sign, shade in ((2, 1, 1.0), (0, 1, 0.75), (0, -1, 0.75), (1, 1, 0.6), (1, -1, 0.6)):
        normal = np.zeros(3)
        normal[axis] = sign
        middle = np.array([*xy, half]) + half * normal
        if normal @ (camera.centre - middle) <= 0:
            continue
        u, v = (np.eye(3)[i] * half for i in range(3) if i != axis)
        corners = np.array([middle - u - v, middle + u - v, middle + u + v, middle - u + v])
        outline = np.concatenate(
            [a + along * (b - a) for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True)]
        )
        pixels = (camera.project(outline) + 0.5) * SUPERSAMPLE - 0.5
        colour = tuple(float(c) * shade for c in rgb)
        cv2.fillPoly(image, [np.round(pixels * 16).astype(np.int32)], colour, cv2.LINE_AA, shift=4)


def _paper(camera: ObliqueCamera, where: board.BoardArgs, size: tuple[int, int]) -> np.ndarray:
    """The table with the printed page lying on it, at the supersampled `size`."""
    page, per_m = board.page_image(dpi=200)
    margin = round(board.MARGIN_M * per_m)
    # Where each pixel sees the page varies smoothly: computed at the centre of every STRIDE x STRIDE block, then
    # interpolated (cv2.resize's linear sampling puts those centres exactly where they belong).
    coarse = (size[0] // STRIDE, size[1] // STRIDE)
    columns, rows = np.meshgrid(np.arange(coarse[0]), np.arange(coarse[1]))
    samples = np.column_stack([columns.ravel(), rows.ravel()]) * STRIDE + (STRIDE - 1) / 2
    on_board = _table_to_board(camera.table_points((samples + 0.5) / SUPERSAMPLE - 0.5), where) * per_m + margin - 0.5
    map_x, map_y = (
        cv2.resize(np.nan_to_num(on_board[:, axis], nan=-1e4).reshape(coarse[::-1]), size).astype(np.float32)
        for axis in (0, 1)
    )
    paper = cv2.remap(page, map_x, map_y, cv2.INTER_LINEAR, borderValue=0).astype(np.float64) / 255
    covered = cv2.remap(np.ones_like(page), map_x, map_y, cv2.INTER_NEAREST, borderValue=0) > 0
    return np.where(covered[..., None], paper[..., None] * (235.0, 235.0, 230.0), TABLE_RGB)


def _table_to_board(xy: np.ndarray, where: board.BoardArgs) -> np.ndarray:
    """The inverse of board.board_to_table."""
    width, height = board.board_size_m()
    yaw = math.radians(where.yaw_deg)
    rotation = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    local = (xy - (where.x, where.y)) @ rotation
    return np.column_stack([-local[:, 1] + width / 2, -local[:, 0] + height / 2])


def _as_webcam(image: np.ndarray, rng: np.random.Generator, quality: int) -> np.ndarray:
    """Uneven light (a gradient across the table and vignetting), lens blur, sensor noise and JPEG."""
    height, width = image.shape[:2]
    rows, columns = np.mgrid[0:height, 0:width]
    angle = rng.uniform(0, 2 * math.pi)
    gradient = 0.85 + 0.25 * ((columns / width - 0.5) * math.cos(angle) + (rows / height - 0.5) * math.sin(angle))
    vignette = 1 - 0.35 * (
        ((columns - width / 2) ** 2 + (rows - height / 2) ** 2) / ((width / 2) ** 2 + (height / 2) ** 2)
    )
    lit = cv2.GaussianBlur(image * (gradient * vignette)[..., None], (0, 0), 0.7)
    noisy = np.clip(lit + rng.normal(0, 3.0, lit.shape), 0, 255).astype(np.uint8)
    _, encoded = cv2.imencode(".jpg", cv2.cvtColor(noisy, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, quality])
    return cv2.cvtColor(cv2.imdecode(encoded, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
