"""Board geometry: bounds, block footprints and overlap, and sampling scenes and free block placements."""

from __future__ import annotations

import math

import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import board

# Gap kept between block footprints when we place blocks, so sims start without contacts.
FOOTPRINT_CLEARANCE = 0.002
# Tries per block before a scene sample starts over (the benchmark allows 20 and then raises).
PLACE_TRIES = 50


def inside_target_bounds(xy) -> bool:
    """The benchmark's `target_inside_bounds`: strictly inside the sampling box."""
    x, y = float(xy[0]), float(xy[1])
    return board.TARGET_X_MIN < x < board.TARGET_X_MAX and board.TARGET_Y_MIN < y < board.TARGET_Y_MAX


def xy(scene: Scene, name: str) -> np.ndarray:
    pose = scene.objects[name]
    return np.array((pose.x, pose.y))


def _half_extents(name: str) -> tuple[float, float]:
    ex, ey = board.block(name).footprint
    return ex / 2 + FOOTPRINT_CLEARANCE / 2, ey / 2 + FOOTPRINT_CLEARANCE / 2


def _box(name: str, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    """Corners (4, 2) and unit axes (2, 2) of the block's footprint rectangle."""
    hx, hy = _half_extents(name)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    axes = np.array(((c, s), (-s, c)))
    local = np.array(((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)))
    return np.array((pose.x, pose.y)) + local @ axes, axes


def footprints_overlap(name_a: str, pose_a: Pose, name_b: str, pose_b: Pose) -> bool:
    """Whether the two blocks' footprint rectangles (with clearance) intersect (separating-axis test)."""
    reach = math.hypot(*_half_extents(name_a)) + math.hypot(*_half_extents(name_b))
    if pose_a.distance_to(pose_b) >= reach:
        return False
    corners_a, axes_a = _box(name_a, pose_a)
    corners_b, axes_b = _box(name_b, pose_b)
    for axis in np.concatenate((axes_a, axes_b)):
        pa, pb = corners_a @ axis, corners_b @ axis
        if pa.max() <= pb.min() or pb.max() <= pa.min():
            return False
    return True


def placement_ok(scene: Scene, name: str, pose: Pose) -> bool:
    """Whether `name` may stand at `pose`: inside the sampling box, clear of the effector and other blocks."""
    if not inside_target_bounds((pose.x, pose.y)):
        return False
    if scene.robot is not None and pose.distance_to(scene.robot) <= board.ARM_DISTANCE_THRESHOLD:
        return False
    return not any(
        footprints_overlap(name, pose, other, other_pose)
        for other, other_pose in scene.objects.items()
        if other != name
    )


def _uniform_xy(rng: np.random.Generator) -> tuple[float, float]:
    x = rng.uniform(board.INNER_X_MIN, board.INNER_X_MAX)
    y = rng.uniform(board.INNER_Y_MIN, board.INNER_Y_MAX)
    return float(x), float(y)


def sample_scene(blocks: tuple[str, ...] | list[str], rng: np.random.Generator) -> Scene:
    """A reset like the benchmark's: effector, then each block uniform in the sampling box.

    Deliberate deviation: the benchmark only keeps block centres 0.0175 m apart and lets physics push
    overlapping blocks apart during 200 settle steps. Our sims reset to exactly the poses an instance
    states, so we require non-overlapping footprints (oriented rectangles plus a small clearance).
    """
    while True:
        scene = Scene(objects={}, robot=Pose(*_uniform_xy(rng), 0.0))
        for name in blocks:
            for _ in range(PLACE_TRIES):
                pose = Pose(*_uniform_xy(rng), float(rng.uniform(0.0, 2 * math.pi)))
                if placement_ok(scene, name, pose):
                    scene = scene.with_object(name, pose)
                    break
            else:
                break  # this block found no room: start the whole scene over
        else:
            return scene


def sample_free_pose(
    scene: Scene,
    name: str,
    rng: np.random.Generator,
    center: np.ndarray | None = None,
    radius: float | None = None,
) -> Pose | None:
    """One candidate pose for moving `name` (keeping its yaw): uniform in the sampling box, or in the disc
    (`center`, `radius`) when given. None when the candidate is not a valid placement."""
    yaw = scene.objects[name].yaw
    if center is None or radius is None:
        pose = Pose(*_uniform_xy(rng), yaw)
    else:
        r = radius * math.sqrt(rng.uniform())
        a = rng.uniform(0.0, 2 * math.pi)
        pose = Pose(float(center[0] + r * math.cos(a)), float(center[1] + r * math.sin(a)), yaw)
    return pose if placement_ok(scene, name, pose) else None
