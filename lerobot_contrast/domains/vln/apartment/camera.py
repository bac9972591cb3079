"""The robot's egocentric RGB-D camera: a pinhole camera ray-cast against the room and furniture volumes.

Every image column is a vertical plane through the camera, so the 2-D footprint intersections are computed
once per column and shared by all its pixels; the per-pixel work is then a few array operations."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment.geometry import Footprints, Room

WALL_COLORS = np.array([[222, 214, 196], [206, 218, 224], [224, 206, 200], [214, 224, 204]], dtype=np.float32)
FLOOR_COLORS = np.array([[176, 142, 104], [160, 128, 92]], dtype=np.float32)
CEILING_COLOR = np.array([240, 240, 236], dtype=np.float32)
LIGHT = np.array([0.6, 0.8])  # a horizontal light direction, so faces of different orientation differ in shade
FLOOR_TILE_M = 0.5
TOP_SHADE = 1.1
# Materials index the palette: walls 0-3, floor tiles 4-5, ceiling 6, then one per furniture item.
FLOOR, CEILING, OBJECTS = 4, 6, 7


@dataclass(frozen=True)
class CameraSpec:
    """Image size, horizontal field of view and mounting height (the LoCoBot's RealSense D435 colour camera
    has a 69 degree HFOV at about 0.55 m). Depth is along the optical axis, in metres, up to `max_depth`."""

    width: int = 640
    height: int = 480
    hfov_deg: float = 69.0
    mount_height: float = 0.55
    max_depth: float = 10.0


class RayCaster:
    def __init__(self, spec: CameraSpec) -> None:
        if spec.width < 1 or spec.height < 1 or not 1.0 <= spec.hfov_deg <= 170.0:
            raise ValueError(f"camera needs a positive size and a field of view in [1, 170] degrees, got {spec}")
        self.spec = spec
        focal = (spec.width / 2) / math.tan(math.radians(spec.hfov_deg) / 2)
        u = np.arange(spec.width) + 0.5
        v = np.arange(spec.height) + 0.5
        left = (spec.width / 2 - u) / focal  # image x grows to the right, the robot's left is +y
        up = (spec.height / 2 - v) / focal
        self.column_angles = np.arctan(left)
        horizontal = np.sqrt(1 + left**2)
        self.depth_scale = (1.0 / horizontal).astype(np.float32)  # horizontal range -> optical-axis depth
        self.slopes = (up[:, None] / horizontal[None, :]).astype(np.float32)  # rise per metre of range
        with np.errstate(divide="ignore"):
            self.inverse_slopes = (1.0 / self.slopes).astype(np.float32)
        self.down = self.slopes < 0
        self._planes_cache: tuple[float, np.ndarray, np.ndarray] | None = None

    def render(self, room: Room, footprints: Footprints, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
        """RGB (H, W, 3) uint8 and depth (H, W) float32 metres seen from the robot at `pose`."""
        origin = np.array([pose.x, pose.y])
        angles = pose.yaw + self.column_angles
        dirs = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
        # Each pixel gets a range, a material (an index into `palette`) and a brightness.
        t, material, shade = self._environment(room, origin, dirs)
        if len(footprints):
            self._furniture(footprints, origin, dirs, t, material, shade)
        depth = np.minimum(t * self.depth_scale[None, :], self.spec.max_depth)
        shade /= 1.0 + 0.04 * t  # a little atmospheric falloff, so depth reads in the image too
        palette = np.concatenate([WALL_COLORS, FLOOR_COLORS, CEILING_COLOR[None], footprints.colors]).astype(np.float32)
        rgb = np.take(palette, material, axis=0)
        rgb *= shade[..., None]
        return np.minimum(rgb, 255, out=rgb).astype(np.uint8), depth

    def _planes(self, wall_height: float) -> tuple[np.ndarray, np.ndarray]:
        """Range to the floor or ceiling and which one (pose-independent, so computed once per room height)."""
        if self._planes_cache is None or self._planes_cache[0] != wall_height:
            h = self.spec.mount_height
            t_floor = np.where(self.down, -h * self.inverse_slopes, np.inf)
            t_ceiling = np.where(self.slopes > 0, (wall_height - h) * self.inverse_slopes, np.inf)
            plane = np.where(self.down, FLOOR, CEILING).astype(np.int32)
            self._planes_cache = (wall_height, np.minimum(t_floor, t_ceiling).astype(np.float32), plane)
        return self._planes_cache[1], self._planes_cache[2]

    def _environment(self, room: Room, origin: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, ...]:
        """Range, material and shade of the walls, floor and ceiling for every pixel."""
        t_plane, plane = self._planes(room.wall_height)
        t_wall, wall = room.exit(origin, dirs)
        t = np.minimum(t_plane, t_wall.astype(np.float32)[None, :])
        material = plane.copy()
        np.copyto(material, wall.astype(np.int32)[None, :], where=t_plane > t)
        x = origin[0] + t * dirs[None, :, 0].astype(np.float32)
        y = origin[1] + t * dirs[None, :, 1].astype(np.float32)
        tile = (np.floor(x / FLOOR_TILE_M) + np.floor(y / FLOOR_TILE_M)).astype(np.int32) & 1
        material += tile * (material == FLOOR)
        return t, material, np.ones(t.shape, dtype=np.float32)

    def _furniture(
        self,
        footprints: Footprints,
        origin: np.ndarray,
        dirs: np.ndarray,
        t: np.ndarray,
        material: np.ndarray,
        shade: np.ndarray,
    ) -> None:
        """Paint the furniture over `t`, `material` and `shade` (in place), nearest surface winning."""
        t_in, t_out, normals = footprints.ray_hits(origin, dirs)
        # Per column, only the footprints its ray crosses matter: few, however much the room holds.
        k = int(np.isfinite(t_in).sum(axis=1).max())
        order = np.argsort(t_in, axis=1)[:, :k]
        side_shade = (0.7 + 0.3 * np.abs(normals @ LIGHT)).astype(np.float32)
        h, s, columns = self.spec.mount_height, self.slopes, np.arange(t_in.shape[0])
        for j in range(k):
            obj = order[:, j]
            near, far = t_in[columns, obj].astype(np.float32), t_out[columns, obj].astype(np.float32)
            height = footprints.heights[obj].astype(np.float32)[None, :]
            z_near = h + s * near[None]
            side = (z_near >= 0) & (z_near <= height)
            t_top = (height - h) * self.inverse_slopes
            top = (z_near > height) & self.down & (t_top <= far[None])
            t_hit = np.full(t.shape, np.inf, dtype=np.float32)
            np.copyto(t_hit, t_top, where=top)
            np.copyto(t_hit, np.broadcast_to(near[None], t.shape), where=side)
            closer = t_hit < t
            np.copyto(t, t_hit, where=closer)
            np.copyto(material, (OBJECTS + obj).astype(np.int32)[None, :], where=closer)
            face = side * (side_shade[columns, obj][None, :] - TOP_SHADE) + TOP_SHADE
            np.copyto(shade, face, where=closer)
