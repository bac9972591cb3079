"""2-D outlines of the Language-Table blocks in the block's local frame (metres, counter-clockwise).

Each outline is scaled to its mesh footprint (board.SHAPE_FOOTPRINT: extent along local x, along local y) and its
bounding box is centred on the origin. The meshes are not shipped here, so the exact profiles are approximations.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from lerobot_contrast.domains.language_table import board

# Foam toy stars are chunkier than the geometric {5/2} star (inner/outer radius 0.38).
STAR_INNER_RATIO = 0.5
# Crescent thickness at its middle as a fraction of the outer radius.
MOON_THICKNESS = 0.42
MOON_SEGMENTS = 14


def _polygon(n_points: int, inner_ratio: float | None = None) -> np.ndarray:
    """A regular polygon (or star, with inner vertices at inner_ratio) with one vertex on +y."""
    n_vertices = 2 * n_points if inner_ratio else n_points
    angles = math.pi / 2 + 2 * math.pi * np.arange(n_vertices) / n_vertices
    radii = np.ones(n_vertices)
    if inner_ratio:
        radii[1::2] = inner_ratio
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


def _crescent() -> np.ndarray:
    """Unit-radius crescent: the outer circle minus a second circle below it; horns at (+-1, 0), belly on +y."""
    # The cutting circle (centre (0, -d), radius r) passes through both horns and leaves MOON_THICKNESS at x = 0.
    t = MOON_THICKNESS
    d = (2 * t - t * t) / (2 * (1 - t))
    r = math.hypot(1.0, d)
    outer = np.linspace(0.0, math.pi, MOON_SEGMENTS + 1)
    horn = math.atan2(d, 1.0)
    inner = np.linspace(math.pi - horn, horn, MOON_SEGMENTS + 1)[1:-1]
    outer_xy = np.stack([np.cos(outer), np.sin(outer)], axis=1)
    inner_xy = np.stack([r * np.cos(inner), r * np.sin(inner) - d], axis=1)
    return np.concatenate([outer_xy, inner_xy])


def _fit(points: np.ndarray, footprint: tuple[float, float]) -> np.ndarray:
    """Scale points to the footprint's bounding box and centre that box on the origin."""
    low, high = points.min(axis=0), points.max(axis=0)
    return (points - (low + high) / 2) / (high - low) * np.asarray(footprint)


@cache
def outline(shape: str) -> np.ndarray:
    """Counter-clockwise outline (N, 2) of a block shape ("cube", "moon", "star", "pentagon"); read-only."""
    raw = {
        "cube": lambda: np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]),
        "moon": _crescent,
        "star": lambda: _polygon(5, STAR_INNER_RATIO),
        "pentagon": lambda: _polygon(5),
    }
    if shape not in raw:
        raise ValueError(f"unknown block shape {shape!r}; choose from: {', '.join(raw)}")
    points = _fit(raw[shape](), board.SHAPE_FOOTPRINT[shape])
    points.setflags(write=False)
    return points


def circle(radius: float, segments: int) -> np.ndarray:
    """Counter-clockwise regular polygon (segments, 2) approximating a circle, for cylinders."""
    angles = 2 * math.pi * np.arange(segments) / segments
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
