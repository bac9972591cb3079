"""Apartment geometry as arrays: the room, furniture footprints, signed distances and ray intersections."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment.furniture import furniture_for


@dataclass(frozen=True)
class Room:
    """The studio: walls at x = 0 and `size_x`, y = 0 and `size_y` (metres), ceiling at `wall_height`."""

    size_x: float = 8.0
    size_y: float = 6.0
    wall_height: float = 2.5

    def wall_distance(self, points: np.ndarray) -> np.ndarray:
        """Distance of each (x, y) point to the nearest wall; negative outside the room."""
        x, y = points[..., 0], points[..., 1]
        return np.minimum(np.minimum(x, self.size_x - x), np.minimum(y, self.size_y - y))

    def exit(self, origin: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance along each unit direction from `origin` (inside) to the wall, and which wall (0..3:
        x = 0, x = size_x, y = 0, y = size_y)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = np.where(dirs[:, 0] > 0, (self.size_x - origin[0]) / dirs[:, 0], -origin[0] / dirs[:, 0])
            ty = np.where(dirs[:, 1] > 0, (self.size_y - origin[1]) / dirs[:, 1], -origin[1] / dirs[:, 1])
        tx = np.where(np.isfinite(tx) & (dirs[:, 0] != 0), tx, np.inf)
        ty = np.where(np.isfinite(ty) & (dirs[:, 1] != 0), ty, np.inf)
        wall = np.where(tx <= ty, np.where(dirs[:, 0] > 0, 1, 0), np.where(dirs[:, 1] > 0, 3, 2))
        return np.minimum(tx, ty), wall


@dataclass(frozen=True)
class Footprints:
    """Furniture as vertical extrusions of boxes and discs; `half` holds box half extents (cylinders: r, r)."""

    names: tuple[str, ...]
    is_box: np.ndarray
    centers: np.ndarray
    yaw: np.ndarray
    half: np.ndarray
    heights: np.ndarray
    colors: np.ndarray

    @classmethod
    def from_objects(cls, objects: Mapping[str, Pose]) -> Footprints:
        names = tuple(objects)
        kinds = [furniture_for(name) for name in names]
        return cls(
            names=names,
            is_box=np.array([k.shape == "box" for k in kinds], dtype=bool),
            centers=np.array([[objects[n].x, objects[n].y] for n in names], dtype=np.float64).reshape(-1, 2),
            yaw=np.array([objects[n].yaw for n in names], dtype=np.float64),
            half=np.array([[k.length / 2, k.width / 2] for k in kinds], dtype=np.float64).reshape(-1, 2),
            heights=np.array([k.height for k in kinds], dtype=np.float64),
            colors=np.array([k.color for k in kinds], dtype=np.float64).reshape(-1, 3),
        )

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def _local(self, points: np.ndarray) -> np.ndarray:
        """Points (P, 2) in every footprint's frame: (P, N, 2)."""
        delta = points[:, None, :] - self.centers[None, :, :]
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        return np.stack([c * delta[..., 0] + s * delta[..., 1], -s * delta[..., 0] + c * delta[..., 1]], axis=-1)

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (P, N) from each point to each footprint's outline; negative inside."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        local = self._local(points)
        q = np.abs(local) - self.half[None]
        outside = np.maximum(q, 0.0)
        box = np.sqrt((outside**2).sum(-1)) + np.minimum(q.max(axis=-1), 0.0)
        disc = np.sqrt((local**2).sum(-1)) - self.half[None, :, 0]
        return np.where(self.is_box[None], box, disc)

    def corners(self, i: int) -> np.ndarray:
        """The four corners (4, 2) of box `i`, counter-clockwise."""
        hx, hy = self.half[i]
        c, s = np.cos(self.yaw[i]), np.sin(self.yaw[i])
        local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
        return self.centers[i] + local @ np.array([[c, s], [-s, c]])

    def sample_points(self, i: int, spacing: float = 0.05) -> np.ndarray:
        """Points covering footprint `i` (outline and interior) at most `spacing` apart, for overlap tests."""
        hx, hy = self.half[i]
        nx, ny = int(np.ceil(2 * hx / spacing)) + 1, int(np.ceil(2 * hy / spacing)) + 1
        local = np.stack(np.meshgrid(np.linspace(-hx, hx, nx), np.linspace(-hy, hy, ny)), -1).reshape(-1, 2)
        if not self.is_box[i]:
            local = local[np.linalg.norm(local, axis=1) <= hx + 1e-9]
            angles = np.linspace(0, 2 * np.pi, max(8, int(2 * np.pi * hx / spacing)), endpoint=False)
            local = np.concatenate([local, hx * np.stack([np.cos(angles), np.sin(angles)], -1)])
        c, s = np.cos(self.yaw[i]), np.sin(self.yaw[i])
        return self.centers[i] + local @ np.array([[c, s], [-s, c]])

    def ray_hits(self, origin: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Entry and exit distances (W, N) of rays `origin + t * dirs[w]` through each footprint (inf where
        missed), and the outward unit normal (W, N, 2) at the entry point."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        rel = origin[None, :] - self.centers
        o = np.stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]], axis=-1)  # (N, 2)
        d = np.stack(
            [c[None] * dirs[:, :1] + s[None] * dirs[:, 1:], -s[None] * dirs[:, :1] + c[None] * dirs[:, 1:]], axis=-1
        )  # (W, N, 2)
        box_in, box_out, box_axis = _slabs(o, d, self.half)
        disc_in, disc_out = _discs(o, d, self.half[:, 0])
        t_in = np.where(self.is_box[None], box_in, disc_in)
        t_out = np.where(self.is_box[None], box_out, disc_out)
        missed = ~(t_out >= np.maximum(t_in, 0.0))
        t_in, t_out = np.where(missed, np.inf, t_in), np.where(missed, np.inf, t_out)
        # Outward normals in each footprint's frame, then rotated back to the world.
        hit_local = o[None] + np.where(np.isfinite(t_in), t_in, 0.0)[..., None] * d
        axis_normal = np.where(box_axis[..., None] == 0, [1.0, 0.0], [0.0, 1.0]) * -np.sign(d)
        disc_normal = hit_local / np.maximum(np.linalg.norm(hit_local, axis=-1, keepdims=True), 1e-9)
        n = np.where(self.is_box[None, :, None], axis_normal, disc_normal)
        world = np.stack([c * n[..., 0] - s * n[..., 1], s * n[..., 0] + c * n[..., 1]], axis=-1)
        return t_in, t_out, world


def _slabs(o: np.ndarray, d: np.ndarray, half: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ray/box intersection by the slab method in each box's frame; also which slab (0: x, 1: y) is entered."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (-half[None] - o[None]) * inv
        t2 = (half[None] - o[None]) * inv
    # A ray parallel to a slab gives +-inf (outside: an empty interval) or nan (on its edge: treat as inside).
    lo = np.nan_to_num(np.minimum(t1, t2), nan=-np.inf, posinf=np.inf, neginf=-np.inf)
    hi = np.nan_to_num(np.maximum(t1, t2), nan=np.inf, posinf=np.inf, neginf=-np.inf)
    return lo.max(axis=-1), hi.min(axis=-1), lo.argmax(axis=-1)


def _discs(o: np.ndarray, d: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    b = (o[None] * d).sum(-1)
    cc = (o * o).sum(-1)[None] - radius[None] ** 2
    disc = b * b - cc
    root = np.sqrt(np.maximum(disc, 0.0))
    hit = disc >= 0
    return np.where(hit, -b - root, np.inf), np.where(hit, -b + root, -np.inf)


def clearance(room: Room, footprints: Footprints, points: np.ndarray) -> np.ndarray:
    """Distance from each point (P, 2) to the nearest wall or furniture outline; negative inside either."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    walls = room.wall_distance(points)
    if len(footprints) == 0:
        return walls
    return np.minimum(walls, footprints.signed_distance(points).min(axis=1))
