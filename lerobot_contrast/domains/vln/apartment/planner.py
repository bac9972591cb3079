"""Shortest routes on an occupancy grid: through a sequence of goal regions, string-pulled to a polyline.

The grid marks cells whose centre keeps the robot's disc clear of walls and furniture. Geodesic distances
are exact on the 8-connected grid (Dijkstra, scipy.sparse.csgraph), and the cell path is then shortened
by line-of-sight checks against the exact geometry, so route lengths approach the continuous optimum."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_array, csr_array
from scipy.sparse.csgraph import dijkstra
from scipy.spatial.distance import directed_hausdorff

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment.geometry import Footprints, Room, clearance

SQRT2 = math.sqrt(2.0)
# (row step, column step, length in cells); rows follow y, columns follow x.
MOVES = tuple((dr, dc, SQRT2 if dr and dc else 1.0) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc)
LINE_SAMPLE_M = 0.02
# Added to every seed's cost on the edge from the virtual source (csgraph reads a zero weight as no edge).
SEED_OFFSET = 1.0


@dataclass(frozen=True)
class Route:
    """A polyline from the start through each goal region; `reached[k]` indexes the point where the route
    enters region k (the end of leg k)."""

    points: np.ndarray
    reached: tuple[int, ...]

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum())


class Grid:
    """Free space for a disc robot of `robot_radius` in a furnished room, at `resolution` metres per cell."""

    def __init__(self, room: Room, footprints: Footprints, robot_radius: float, resolution: float = 0.1) -> None:
        self.room, self.footprints, self.robot_radius, self.resolution = room, footprints, robot_radius, resolution
        self.shape = (int(round(room.size_y / resolution)), int(round(room.size_x / resolution)))
        rows, cols = np.indices(self.shape)
        self.centers = np.stack([(cols + 0.5) * resolution, (rows + 0.5) * resolution], axis=-1)
        flat = self.centers.reshape(-1, 2)
        self._object_distance = footprints.signed_distance(flat).reshape(*self.shape, len(footprints))
        walls = room.wall_distance(self.centers)
        self.clearance = np.minimum(walls, self._object_distance.min(axis=-1)) if len(footprints) else walls
        self.free = self.clearance > robot_radius
        self._moves = self._move_graph()

    def region(self, name: str, radius: float) -> np.ndarray:
        """Free cells whose centre lies within `radius` of furniture `name`'s outline."""
        if name not in self.footprints.names:
            return np.zeros(self.shape, dtype=bool)
        return self.free & (self._object_distance[..., self.footprints.index(name)] <= radius)

    def cell(self, xy: tuple[float, float]) -> tuple[int, int] | None:
        """The free cell nearest to `xy` (within two cells), or None when the robot cannot stand there."""
        col, row = int(xy[0] / self.resolution), int(xy[1] / self.resolution)
        best, best_d = None, math.inf
        for r in range(row - 2, row + 3):
            for c in range(col - 2, col + 3):
                if 0 <= r < self.shape[0] and 0 <= c < self.shape[1] and self.free[r, c]:
                    d = math.dist(self.centers[r, c], xy)
                    if d < best_d:
                        best, best_d = (r, c), d
        return best

    def route(self, start: Pose, regions: list[np.ndarray]) -> Route | None:
        """The shortest route from `start` entering each region in order, or None if there is none."""
        first = self.cell((start.x, start.y))
        if first is None or not regions or not all(region.any() for region in regions):
            return None
        seeds = np.full(self.shape, np.inf)
        seeds[first] = 0.0
        fields = []
        for region in regions:
            field = self.geodesic(seeds)
            fields.append((field, seeds))
            seeds = np.where(region, field, np.inf)
        if not np.isfinite(seeds).any():
            return None
        cell = np.unravel_index(int(np.argmin(seeds)), self.shape)
        legs = []
        for field, leg_seeds in reversed(fields):
            leg = self._backtrack(field, leg_seeds, cell)
            legs.append(leg)
            cell = leg[0]
        return self._polyline(start, list(reversed(legs)))

    def geodesic(self, seeds: np.ndarray) -> np.ndarray:
        """Shortest 8-connected path length (metres) from the seeds (cells with their initial cost) to every
        cell; inf where unreachable. Diagonal moves may not cut the corner of a blocked cell."""
        n = self.free.size
        start = np.flatnonzero(np.isfinite(seeds) & self.free)
        source = coo_array(
            (seeds.reshape(-1)[start] + SEED_OFFSET, (np.full(len(start), n), start)), shape=(n + 1, n + 1)
        )
        distance = dijkstra(self._moves + source.tocsr(), directed=True, indices=n)[:n] - SEED_OFFSET
        # Equal-length paths summed in different orders differ by rounding: make them tie exactly.
        return np.round(distance, 9).reshape(self.shape)

    def segment_free(self, a: np.ndarray, b: np.ndarray) -> bool:
        n = max(2, int(math.dist(a, b) / LINE_SAMPLE_M) + 1)
        samples = a[None] + np.linspace(0.0, 1.0, n)[:, None] * (b - a)[None]
        return bool((clearance(self.room, self.footprints, samples) >= self.robot_radius).all())

    def _move_graph(self) -> csr_array:
        """The allowed unit moves between free cells as a sparse graph (metres), with one more node, the
        virtual source `geodesic` links to its seeds."""
        n = self.free.size
        index = np.arange(n).reshape(self.shape)
        rows, cols = np.indices(self.shape)
        sources, targets, weights = [], [], []
        for dr, dc, length in MOVES:
            dst, src = _slices(dr, dc)
            allowed = self.free[dst] & self.free[src]
            if dr and dc:  # both cells beside the diagonal must be free too
                r, c = rows[dst], cols[dst]
                allowed &= self.free[r - dr, c] & self.free[r, c - dc]
            sources.append(index[src][allowed])
            targets.append(index[dst][allowed])
            weights.append(np.full(int(allowed.sum()), length * self.resolution))
        edges = (np.concatenate(weights), (np.concatenate(sources), np.concatenate(targets)))
        return coo_array(edges, shape=(n + 1, n + 1)).tocsr()

    def _backtrack(self, field: np.ndarray, seeds: np.ndarray, end: tuple[int, int]) -> list[tuple[int, int]]:
        """Cells from a seed to `end`, stepping to the neighbour that explains each cell's distance."""
        path = [end]
        cell = end
        while field[cell] < seeds[cell] - 1e-9:  # a seed whose own cost explains it ends the leg
            r, c = cell
            best, best_value = None, math.inf
            for dr, dc, length in MOVES:
                pr, pc = r - dr, c - dc
                if not (0 <= pr < self.shape[0] and 0 <= pc < self.shape[1]) or not self.free[pr, pc]:
                    continue
                if dr and dc and not (self.free[r - dr, c] and self.free[r, c - dc]):
                    continue
                value = field[pr, pc] + length * self.resolution
                if value < best_value:
                    best, best_value = (pr, pc), value
            if best is None:
                break
            cell = best
            path.append(cell)
        return path[::-1]

    def _polyline(self, start: Pose, legs: list[list[tuple[int, int]]]) -> Route:
        points = [np.array([start.x, start.y])]
        reached = []
        for leg in legs:
            cells = [self.centers[cell] for cell in leg]
            points.extend(self._pull(points[-1], cells))
            reached.append(len(points) - 1)
        return Route(points=np.array(points), reached=tuple(reached))

    def _pull(self, origin: np.ndarray, cells: list[np.ndarray]) -> list[np.ndarray]:
        """Greedy string pulling: from each kept point, jump to the farthest cell still in line of sight."""
        kept, anchor, i = [], origin, 0
        while i < len(cells):
            j = i
            while j + 1 < len(cells) and self.segment_free(anchor, cells[j + 1]):
                j += 1
            kept.append(cells[j])
            anchor, i = cells[j], j + 1
        return kept


def _slices(dr: int, dc: int) -> tuple[tuple[slice, slice], tuple[slice, slice]]:
    """Views of the destination cells and of their sources (the cells (dr, dc) behind them)."""

    def span(step: int) -> tuple[slice, slice]:
        if step > 0:
            return slice(step, None), slice(None, -step)
        if step < 0:
            return slice(None, step), slice(-step, None)
        return slice(None), slice(None)

    (rd, rs), (cd, cs) = span(dr), span(dc)
    return (rd, cd), (rs, cs)


def hausdorff(a: np.ndarray, b: np.ndarray, spacing: float = 0.05) -> float:
    """Symmetric Hausdorff distance between two polylines, sampled every `spacing` metres."""
    pa, pb = resample(a, spacing), resample(b, spacing)
    return float(max(directed_hausdorff(pa, pb)[0], directed_hausdorff(pb, pa)[0]))


def resample(points: np.ndarray, spacing: float) -> np.ndarray:
    """Points along a polyline every `spacing` metres of arc length, with its vertices (so corners, where a
    path comes closest to what it turns around, are kept)."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(points) < 2:
        return points
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    if arc[-1] == 0.0:
        return points[:1]
    s = np.union1d(np.arange(0.0, arc[-1], spacing), arc)
    return np.stack([np.interp(s, arc, points[:, 0]), np.interp(s, arc, points[:, 1])], axis=-1)
