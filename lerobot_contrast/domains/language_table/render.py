"""Fast CPU renderer of the Language-Table tabletop as the benchmark camera sees it.

Painter's algorithm with cv2 polygon fills: blocks are extruded outlines, the effector a vertical cylinder, and the
ground and board are painted once per renderer.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from lerobot_contrast.domains.language_table import board, shapes
from lerobot_contrast.domains.language_table.camera import Camera

# pybullet's TinyRenderer lights with ambient 0.6 + diffuse 0.35 * max(0, n.l); the light sits high above the board.
AMBIENT, DIFFUSE = 0.6, 0.35
LIGHT = np.array([0.4, 0.3, 1.0]) / math.hypot(0.4, 0.3, 1.0)
# plane.obj repeats its 2x2 checker texture 15 times over 30 m, so one ground tile is 1 m.
GROUND_TILE = 1.0
GROUND_RGB = np.array([(90, 120, 200), (226, 226, 226)], dtype=np.uint8)
EFFECTOR_RGB = (222, 222, 222)
# The cylinder's top only has to clear the image's top edge (z ~0.4 at x = 0.6) while staying below the camera.
EFFECTOR_Z = (0.005, 0.45)
EFFECTOR_SEGMENTS = 16
# Bodies with any vertex closer than this along the optical axis (or behind the camera) are skipped.
NEAR = 0.05
SHIFT = 4  # cv2 fixed-point fraction bits, for sub-pixel polygon edges


@dataclass(frozen=True)
class _Layout:
    """Outline vertices of a fixed list of bodies (blocks, then the effector), stacked for one-shot transforms."""

    local: np.ndarray  # (V, 2) outline vertices in each body's frame
    normals: np.ndarray  # (V, 2) outward normal of the side face from vertex i to next[i]
    body: np.ndarray  # (V,) owning body of each vertex
    next: np.ndarray  # (V,) following vertex on the same outline
    z: np.ndarray  # (2, V) bottom and top height of each vertex
    starts: np.ndarray  # (B + 1,) first vertex of each body
    colors: np.ndarray  # (B, 3) lit top-face colour of each body

    @classmethod
    def build(cls, names: tuple[str, ...]) -> _Layout:
        outlines = [shapes.outline(_shape(name)) for name in names]
        outlines.append(shapes.circle(board.EFFECTOR_RADIUS, EFFECTOR_SEGMENTS))
        sizes = np.array([len(o) for o in outlines])
        starts = np.concatenate([[0], np.cumsum(sizes)])
        local = np.concatenate(outlines)
        body = np.repeat(np.arange(len(outlines)), sizes)
        nxt = np.arange(len(local)) + 1
        nxt[starts[1:] - 1] = starts[:-1]
        edges = local[nxt] - local
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1) / np.linalg.norm(edges, axis=1, keepdims=True)
        heights = [(0.0, board.BLOCK_HEIGHT)] * len(names) + [EFFECTOR_Z]
        z = np.repeat(np.array(heights), sizes, axis=0).T
        colors = np.array([board.COLOR_RGB[name.split("_")[0]] for name in names] + [EFFECTOR_RGB], dtype=float)
        return cls(local, normals, body, nxt, z, starts, colors)


@dataclass(frozen=True)
class _Frame:
    """Per-render geometry of a _Layout at given poses."""

    base: np.ndarray  # (V, 2) world xy of each outline vertex
    depth: np.ndarray  # (V,) nearer of the bottom and top vertex depths
    pixels: np.ndarray  # (2V, 2) fixed-point pixels of the bottom then the top vertices
    normals: np.ndarray  # (2, V) world xy of each side face's outward normal
    drawn: np.ndarray  # (B,) bodies in front of the camera (and the effector, when given)


def _shape(name: str) -> str:
    color, _, shape = name.partition("_")
    if color not in board.COLOR_RGB or shape not in board.SHAPE_FOOTPRINT:
        raise ValueError(f"cannot render object {name!r}: expected a block name such as 'red_moon'")
    return shape


def _pose_rows(poses: Any) -> list[tuple[float, float, float]]:
    """(x, y, yaw) tuples, or Pose-like objects with .x/.y/.yaw, as plain tuples."""
    return [(p.x, p.y, p.yaw) if hasattr(p, "yaw") else tuple(p) for p in poses]


class TabletopRenderer:
    """Renders blocks and the effector into (height, width, 3) uint8 RGB frames from the benchmark camera."""

    def __init__(self, height: int = board.IMAGE_HEIGHT, width: int = board.IMAGE_WIDTH) -> None:
        self.camera = Camera(height, width)
        self._background = self._paint_background()
        self._layouts: dict[tuple[str, ...], _Layout] = {}
        self._top_shade = AMBIENT + DIFFUSE * LIGHT[2]

    def project(self, points_xyz: np.ndarray) -> np.ndarray:
        """World points (N, 3) -> continuous pixel coordinates (N, 2) as (col, row)."""
        return self.camera.project(points_xyz)

    def render_scene(self, scene: Any) -> np.ndarray:
        """Render a contrast.scene.Scene: its objects as blocks, scene.robot (if any) as the effector."""
        return self.render(scene)

    def render(self, blocks: Any, effector_xy: tuple[float, float] | None = None) -> np.ndarray:
        """Render {block name: (x, y, yaw) or Pose} (or a Scene) with the effector at effector_xy (None: no effector)."""
        if not isinstance(blocks, Mapping):  # a Scene: its robot is the effector unless effector_xy is given
            robot = blocks.robot
            if effector_xy is None and robot is not None:
                effector_xy = (robot.x, robot.y)
            blocks = blocks.objects
        names = tuple(blocks)
        layout = self._layouts.get(names)
        if layout is None:
            layout = self._layouts[names] = _Layout.build(names)
        poses = np.array([*_pose_rows(blocks.values()), (*(effector_xy or (0.0, 0.0)), 0.0)], dtype=float)
        image = self._background.copy()
        self._paint_bodies(image, layout, poses, effector_xy is not None)
        return image

    def _paint_bodies(self, image: np.ndarray, layout: _Layout, poses: np.ndarray, effector: bool) -> None:
        frame = self._place(layout, poses, effector)
        order, faces, nxt, face_colors, counts = self._schedule(layout, poses, frame)
        bottom, top = np.split(frame.pixels, 2)
        quads = np.stack([bottom[faces], bottom[nxt], top[nxt], top[faces]], axis=1)
        top_colors = layout.colors.tolist()
        first = 0
        for body, count in zip(order.tolist(), counts, strict=True):
            for k in range(first, first + count):
                cv2.fillConvexPoly(image, quads[k], face_colors[k], cv2.LINE_8, SHIFT)
            first += count
            if body < len(poses) - 1:  # the effector's top end is above the image
                outline = top[layout.starts[body] : layout.starts[body + 1]]
                cv2.fillPoly(image, [outline], top_colors[body], cv2.LINE_8, SHIFT)

    def _place(self, layout: _Layout, poses: np.ndarray, effector: bool) -> _Frame:
        """Move every outline to its pose, then project bottom and top vertices in one call."""
        cos, sin = np.cos(poses[:, 2])[layout.body], np.sin(poses[:, 2])[layout.body]
        lx, ly = layout.local.T
        n_vertices = len(lx)
        points = np.empty((2 * n_vertices, 3))
        points[:n_vertices, 0] = points[n_vertices:, 0] = cos * lx - sin * ly + poses[layout.body, 0]
        points[:n_vertices, 1] = points[n_vertices:, 1] = sin * lx + cos * ly + poses[layout.body, 1]
        points[:, 2] = layout.z.ravel()
        cam = self.camera.to_camera(points)
        depth = np.minimum(cam[:n_vertices, 2], cam[n_vertices:, 2])
        drawn = np.minimum.reduceat(depth, layout.starts[:-1]) > NEAR
        drawn[-1] &= effector
        with np.errstate(all="ignore"):  # skipped bodies may sit behind the camera
            pixels = np.round((self.camera.project_camera(cam) - 0.5) * (1 << SHIFT)).astype(np.int32)
        lnx, lny = layout.normals.T
        normals = np.stack([cos * lnx - sin * lny, sin * lnx + cos * lny])
        return _Frame(points[:n_vertices, :2], depth, pixels, normals, drawn)

    def _schedule(self, layout: _Layout, poses: np.ndarray, frame: _Frame) -> tuple:
        """Painting order: bodies far to near, each one's camera-facing side faces far to near, then its top."""
        nx, ny = frame.normals
        to_face = frame.base - self.camera.eye[:2]
        facing = to_face[:, 0] * nx + to_face[:, 1] * ny < 0
        faces = np.flatnonzero(frame.drawn[layout.body] & facing)
        # The measured block colours are lit top faces; sides keep their brightness relative to the top.
        shade = (AMBIENT + DIFFUSE * np.maximum(0.0, nx[faces] * LIGHT[0] + ny[faces] * LIGHT[1])) / self._top_shade
        centers = np.column_stack([poses[frame.drawn, :2], np.zeros(int(frame.drawn.sum()))])
        order = np.flatnonzero(frame.drawn)[np.argsort(-self.camera.to_camera(centers)[:, 2], kind="stable")]
        rank = np.empty(len(poses), dtype=int)
        rank[order] = np.arange(len(order))
        nxt = layout.next[faces]
        sort = np.lexsort((-(frame.depth[faces] + frame.depth[nxt]), rank[layout.body[faces]]))
        faces, nxt, shade = faces[sort], nxt[sort], shade[sort]
        face_colors = (layout.colors[layout.body[faces]] * shade[:, None]).tolist()
        counts = np.bincount(rank[layout.body[faces]], minlength=len(order)).tolist()
        return order, faces, nxt, face_colors, counts

    def _paint_background(self) -> np.ndarray:
        """Checkered ground and the dark board, by casting each pixel's ray onto the table plane."""
        rays = self.camera.pixel_rays()
        eye = self.camera.eye
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(rays[..., 2] < 0, -eye[2] / rays[..., 2], np.inf)
        x, y = eye[0] + t * rays[..., 0], eye[1] + t * rays[..., 1]
        finite = np.isfinite(t)
        parity = (np.floor(np.where(finite, x, 0) / GROUND_TILE) + np.floor(np.where(finite, y, 0) / GROUND_TILE)) % 2
        image = GROUND_RGB[parity.astype(int)]
        (cx, cy), (sx, sy) = board.BOARD_CENTER, board.BOARD_SIZE
        on_board = finite & (np.abs(x - cx) <= sx / 2) & (np.abs(y - cy) <= sy / 2)
        image[on_board] = board.BOARD_RGB
        return np.ascontiguousarray(image)
