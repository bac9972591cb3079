"""Seeing the scene with the calibrated camera, for an operator that works alone: every coloured object's position
and a cube's yaw (modulo its quarter turn), whether it rests on the table, inside a bin, or is held in the gripper,
and which objects could not be seen. It reads camera frames and the arm's own joint readings, nothing else."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import cv2
import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.staging import locate
from lerobot_contrast.staging.check import BenchGeometry
from lerobot_contrast.staging.homography import CameraCalibration

HELD_PX = 40  # a blob of an object's colour this near the jaws' image is the object in them
HELD_ABOVE = 1.5  # jaws higher than this many object sizes carry what they hold clear of the table
TOP_SHARE = 0.5  # the brightest share of a cube's pixels is its top face, lit from above
ARM_RADIUS_M = 0.035  # masked around each point of the arm's links: about the links' half width


@dataclass(frozen=True)
class Sighting:
    """Where the camera sees one object: its centre (metres, robot frame), a cube's yaw in [-pi/4, pi/4) (None where
    its outline says nothing), and whether it hangs in the gripper."""

    x: float
    y: float
    z: float
    yaw: float | None
    held: bool = False

    def pose(self) -> tuple[float, float, float, float]:
        return self.x, self.y, self.z, self.yaw or 0.0


@dataclass(frozen=True)
class View:
    """One look at the table: what was seen and what was not (by name)."""

    seen: Mapping[str, Sighting]
    unseen: tuple[str, ...]
    waiting: tuple[str, ...] = ()  # seen in the tray, off the workspace

    def scene(self, believed: Scene) -> Scene:
        """`believed` with every object on the table where it was seen (held ones stay where they were believed),
        and none of those waiting in the tray that `believed` does not have (one it has was pushed into the tray)."""
        objects = dict(believed.objects)
        for name, sighting in self.seen.items():
            if name in self.waiting and name not in believed.objects:
                continue
            if not sighting.held:
                objects[name] = Pose(sighting.x, sighting.y, sighting.yaw or 0.0)
        return Scene(objects, believed.robot)


def look(
    image: np.ndarray | None,
    calibration: CameraCalibration,
    geometry: BenchGeometry,
    jaws: tuple[float, float, float] | None = None,
    arm: np.ndarray | None = None,
) -> View:
    """Locate each of `geometry`'s coloured objects in `image`; `jaws` (x, y, z of the point between the gripper's
    pads, from the arm's joint readings) says where a held object would hang; `arm` (N, 3) points along the arm's
    links, whose image is masked out (an arm of an object's colour is not that object)."""
    if image is None:
        return View({}, tuple(geometry.colours))
    size = geometry.size
    holding = jaws is not None and jaws[2] > HELD_ABOVE * size
    held = (
        _held(image, calibration, geometry, jaws, arm) if holding else {}
    )  # before the arm (and what it holds) is masked
    if arm is not None and len(arm):
        image = _without_arm(image, calibration, arm)
    table = locate.find_objects(image, calibration, geometry.colours, geometry.bounds, size)
    seen: dict[str, Sighting] = dict(held)
    for name, (x, y) in table.items():
        if name not in seen:
            top = top_face(image, locate.colour_mask(image, geometry.colours[name]), calibration, (x, y), size)
            if top is None:
                seen[name] = Sighting(x, y, size / 2, None)
            else:
                seen[name] = Sighting(top[0], top[1], size / 2, top[2])
    unseen = tuple(name for name in geometry.colours if name not in seen)
    waiting = tuple(name for name, at in seen.items() if not at.held and geometry.waiting(at.x, at.y))
    return View(seen, unseen, waiting)


def _without_arm(image: np.ndarray, calibration: CameraCalibration, arm: np.ndarray) -> np.ndarray:
    """`image` with a grey disc over each point of the arm: no colour band matches grey."""
    masked = image.copy()
    pixels = np.concatenate([calibration.lift(point[None, :2], point[2]) for point in arm])
    for point, (column, row) in zip(arm, pixels, strict=True):
        radius = ARM_RADIUS_M * _pixels_per_metre(calibration, (point[0], point[1]), point[2])
        cv2.circle(masked, (round(column), round(row)), max(1, round(radius)), (128, 128, 128), -1)
    return masked


def _held(image, calibration: CameraCalibration, geometry: BenchGeometry, jaws, arm) -> dict[str, Sighting]:
    """The object whose colour shows most at the jaws' image: held there. A colour that also shows at the arm's
    shoulder is the arm's own, not an object's."""
    x, y, z = jaws
    at_jaws = calibration.lift(np.array([[x, y]]), z)[0]
    at_shoulder = None if arm is None or not len(arm) else calibration.lift(arm[:1, :2], arm[0, 2])[0]
    counts = {}
    for name, colour in geometry.colours.items():
        rows, columns = np.nonzero(locate.colour_mask(image, colour))
        pixels = np.column_stack([columns, rows])
        if at_shoulder is not None and (np.hypot(*(pixels - at_shoulder).T) < HELD_PX).sum() >= locate.MIN_PIXELS:
            continue
        counts[name] = int((np.hypot(*(pixels - at_jaws).T) < HELD_PX).sum())
    best = max(counts, key=counts.get, default=None)
    if best is None or counts[best] < locate.MIN_PIXELS:
        return {}
    return {best: Sighting(x, y, z, None, held=True)}


def top_face(
    image: np.ndarray, mask: np.ndarray, calibration: CameraCalibration, at: tuple[float, float], size: float
) -> tuple[float, float, float] | None:
    """A cube's centre (x, y) and its yaw modulo a quarter turn, from its top face (its brightest pixels, lit from
    above) near `at`, projected onto the plane of the top: the centre is the mean of those points, the yaw the
    smallest rectangle's around them. The top's centre lies over the cube's own, where the whole blob's centroid
    (sides included, as each colour's shading lets them show) does not: on the twin, measured with
    scripts/bench/bench_seeing.py, the blob's centroid put cubes 1.05 cm off at the 95th percentile (a green one
    1.2 cm), the top's mean 0.17 cm."""
    centre = calibration.lift(np.array([at]), size / 2)[0]
    rows, columns = np.nonzero(mask)
    pixels = np.column_stack([columns, rows]).astype(np.float64)
    near = np.hypot(*(pixels - centre).T) < 4 * _pixels_per_metre(calibration, at, size / 2) * size
    if near.sum() < locate.MIN_PIXELS:
        return None
    value = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)[rows[near], columns[near], 2].astype(float)
    lit = value >= np.quantile(value, 1 - TOP_SHARE)
    top = calibration.to_table(pixels[near][lit], size)
    points = top.astype(np.float32)
    inside = np.linalg.norm(top - np.median(top, axis=0), axis=1) < size
    if inside.sum() < locate.MIN_PIXELS:
        return None
    (_, _), (_, _), angle = cv2.minAreaRect(points[inside])
    x, y = top[inside].mean(axis=0)
    return float(x), float(y), _quarter(math.radians(angle))


def _pixels_per_metre(calibration: CameraCalibration, at: tuple[float, float], height: float) -> float:
    """How many pixels a centimetre at (x, y) `height` above the table spans, per metre."""
    ends = calibration.lift(np.array([at, (at[0] + 0.01, at[1])]), height)
    return float(np.linalg.norm(ends[1] - ends[0]) / 0.01)


def _quarter(angle: float) -> float:
    """`angle` modulo a quarter turn, in [-pi/4, pi/4)."""
    return (angle + math.pi / 4) % (math.pi / 2) - math.pi / 4


def yaw_error(a: float, b: float) -> float:
    """How far apart two cube yaws are, modulo the cube's quarter-turn symmetry (radians, at most pi/4)."""
    return abs(_quarter(a - b))
