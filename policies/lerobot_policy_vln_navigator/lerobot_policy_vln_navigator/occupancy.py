"""The navigator's map: an occupancy grid in the odometry frame built from the scanner's own predicted ranges (and
the bumper), and a geodesic planner on it that turns a set of goal points into the next discrete command."""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.ndimage import binary_dilation, distance_transform_edt, uniform_filter
from scipy.sparse import coo_array, csr_array
from scipy.sparse.csgraph import dijkstra

# Log-odds evidence: a ray's end is a hit, the cells it passed are free; clamped so a later view can overturn it.
HIT, MISS, LOW, HIGH, OCCUPIED = 1.5, 0.4, -2.0, 4.0, 0.5
MOVES = [(dr, dc, math.hypot(dr, dc)) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]


class OccupancyMap:
    """A square grid of `2 * half_m` metres around where the episode started, at `resolution` metres per cell."""

    def __init__(self, origin: tuple[float, float], resolution: float = 0.1, half_m: float = 12.0) -> None:
        self.resolution = resolution
        self.corner = np.array(origin, np.float64) - half_m
        n = int(round(2 * half_m / resolution))
        self.evidence = np.zeros((n, n), np.float32)
        self.seen = np.zeros((n, n), bool)
        self.bumped = np.zeros((n, n), bool)

    def cells(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) of points (P, 2), clipped to the grid."""
        ij = np.floor((np.asarray(xy, np.float64) - self.corner) / self.resolution).astype(int)
        ij = np.clip(ij, 0, self.evidence.shape[0] - 1)
        return ij[..., 1], ij[..., 0]

    def add_scan(self, pose: np.ndarray, bearings: np.ndarray, ranges: np.ndarray, max_range: float) -> None:
        """Rays from `pose` (x, y, yaw) along `bearings` ended at `ranges`; one at `max_range` met nothing."""
        angles = pose[2] + bearings
        dirs = np.stack([np.cos(angles), np.sin(angles)], -1)
        steps = np.arange(0.0, max_range, self.resolution / 2)
        passed = steps[None, :] < (ranges[:, None] - self.resolution)
        points = pose[None, None, :2] + steps[None, :, None] * dirs[:, None, :]
        rows, cols = self.cells(points[passed])
        flat = np.unique(rows * self.evidence.shape[1] + cols)
        self.evidence.flat[flat] -= MISS
        self.seen.flat[flat] = True
        ends = ranges < max_range - 0.2
        rows, cols = self.cells(pose[None, :2] + ranges[ends, None] * dirs[ends])
        np.add.at(self.evidence, (rows, cols), HIT)
        self.seen[rows, cols] = True
        np.clip(self.evidence, LOW, HIGH, out=self.evidence)
        self.evidence[self.bumped] = HIGH  # what the bumper touched stays an obstacle, whatever the camera says

    def add_bump(self, pose: np.ndarray, ahead_m: float) -> None:
        """The bumper touched something `ahead_m` in front of the robot's centre."""
        xy = pose[:2] + ahead_m * np.array([math.cos(pose[2]), math.sin(pose[2])])
        rows, cols = self.cells(xy[None])
        self.evidence[rows, cols] = HIGH
        self.seen[rows, cols] = self.bumped[rows, cols] = True


class Planner:
    """Geodesic cost-to-go over the window of the map seen so far: cells within `radius_m` of an obstacle cost
    `blocked` times their length (not infinite: a misread range must not wall the robot in), cells near one cost
    more, so routes keep `clearance_m` where they can."""

    def __init__(self, radius_m: float, clearance_m: float, blocked: float = 25.0, margin: int = 6) -> None:
        self.radius_m, self.clearance_m, self.blocked, self.margin = radius_m, clearance_m, blocked, margin

    def window(self, grid: OccupancyMap, pose: np.ndarray) -> tuple[slice, slice]:
        """The rows and columns around every seen cell and the robot."""
        r, c = (int(v[0]) for v in grid.cells(pose[None, :2]))
        rows, cols = np.nonzero(grid.seen.any(axis=1))[0], np.nonzero(grid.seen.any(axis=0))[0]
        n = grid.evidence.shape[0]
        r0, r1 = min(rows.min(initial=r), r), max(rows.max(initial=r), r)
        c0, c1 = min(cols.min(initial=c), c), max(cols.max(initial=c), c)
        return (
            slice(max(0, r0 - self.margin), min(n, r1 + self.margin + 1)),
            slice(max(0, c0 - self.margin), min(n, c1 + self.margin + 1)),
        )

    def field(self, grid: OccupancyMap, window: tuple[slice, slice], goals: np.ndarray) -> np.ndarray:
        """Cost-to-go (metres) from every cell of `window` to the nearest `goals` cell (a boolean window)."""
        occupied = grid.evidence[window] > OCCUPIED
        if occupied.any():
            clearance = distance_transform_edt(~occupied) * grid.resolution
        else:
            clearance = np.full(occupied.shape, np.inf)
        weight = 1.0 + 4.0 * np.clip((self.radius_m + self.clearance_m - clearance) / self.clearance_m, 0.0, 1.0)
        weight = np.where(clearance <= self.radius_m, self.blocked, weight)
        return _geodesic(weight * grid.resolution, goals)


def goal_cells(
    grid: OccupancyMap, window: tuple[slice, slice], points: np.ndarray, within_m: float, share: float = 0.1
) -> np.ndarray:
    """Cells of `window` within `within_m` of where `points` (P, 2) gather: a 3 x 3 neighbourhood holding at least
    two points and `share` of the densest one's, so a few columns that misread the class or range do not make a
    goal beside the object seen many times."""
    counts = np.zeros(grid.evidence.shape, np.float32)
    rows, cols = grid.cells(points)
    np.add.at(counts, (rows, cols), 1.0)
    density = uniform_filter(counts[window], 3) * 9
    dense = density >= max(2.0, share * density.max(initial=0.0))
    k = int(math.ceil(within_m / grid.resolution))
    disc = np.hypot(*np.mgrid[-k : k + 1, -k : k + 1]) <= k
    return binary_dilation(dense & (counts[window] > 0), disc)


def frontier_cells(grid: OccupancyMap, window: tuple[slice, slice]) -> np.ndarray:
    """Seen free cells of `window` beside unseen ones, away from obstacles: where exploring reveals the most."""
    seen, occupied = grid.seen[window], grid.evidence[window] > OCCUPIED
    return seen & ~occupied & binary_dilation(~seen) & ~binary_dilation(occupied, iterations=2)


def _geodesic(cost: np.ndarray, seeds: np.ndarray) -> np.ndarray:
    """8-connected shortest path cost from the seed cells, moving into a cell paying its cost per cell length."""
    shape = cost.shape
    starts = np.flatnonzero(seeds)
    if starts.size == 0:
        return np.full(shape, np.inf)
    edges, half_length, indices, indptr = _grid_graph(shape)
    flat = cost.ravel()
    weights = half_length.astype(flat.dtype) * (flat[edges[0]] + flat[edges[1]])
    graph = csr_array((weights, indices, indptr), shape=(cost.size, cost.size))
    # Every move's cost is the same both ways, so one multi-source search from the seeds gives the cost-to-go.
    return dijkstra(graph, directed=True, indices=starts, min_only=True).reshape(shape)


@functools.lru_cache(maxsize=64)
def _grid_graph(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The 8-connected graph of a grid of `shape`, once per shape (the planner's windows take few): each edge's
    source and target cell and half its length, in the order of its CSR layout, with that layout's column indices
    and row pointers."""
    index = np.arange(shape[0] * shape[1]).reshape(shape)
    sources, targets, lengths = [], [], []
    for dr, dc, length in MOVES:
        src = index[max(0, -dr) : shape[0] - max(0, dr), max(0, -dc) : shape[1] - max(0, dc)].ravel()
        sources.append(src)
        targets.append(index[max(0, dr) : shape[0] + min(0, dr), max(0, dc) : shape[1] + min(0, dc)].ravel())
        lengths.append(np.full(src.size, length * 0.5))
    rows, cols = np.concatenate(sources), np.concatenate(targets)
    # The layout scipy gives these edges, found by carrying each edge's number (exact in float64) through it.
    layout = coo_array((np.arange(1, rows.size + 1, dtype=np.float64), (rows, cols)), shape=(index.size,) * 2).tocsr()
    order = layout.data.astype(np.int64) - 1
    return np.stack([rows[order], cols[order]]), np.concatenate(lengths)[order], layout.indices, layout.indptr
