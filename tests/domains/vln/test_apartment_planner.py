"""Shortest routes on the occupancy grid through goal regions."""

from __future__ import annotations

import math
from itertools import pairwise

import numpy as np
import pytest

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment import Footprints, Grid, Room, clearance, hausdorff


def grid(objects: dict[str, Pose], resolution: float = 0.1) -> Grid:
    return Grid(Room(), Footprints.from_objects(objects), robot_radius=0.18, resolution=resolution)


def test_in_an_open_room_the_route_is_straight_to_the_nearest_point_of_the_region():
    g = grid({"lamp": Pose(6.0, 3.0)})
    route = g.route(Pose(1.0, 3.0), [g.region("lamp", 0.5)])
    assert route is not None and len(route.points) == 2
    assert route.length == pytest.approx(6.0 - 0.175 - 0.5 - 1.0, abs=0.1)


def test_geodesic_distances_are_exact_on_the_eight_connected_grid():
    g = grid({})
    seeds = np.full(g.shape, np.inf)
    seeds[10, 10] = 0.0
    field = g.geodesic(seeds)
    assert field[13, 14] == pytest.approx((3 * math.sqrt(2) + 1) * 0.1)
    assert field[10, 30] == pytest.approx(2.0)


def test_routes_go_around_furniture_and_keep_the_robot_clear_of_it():
    wall = {
        "bookshelf": Pose(4.0, 2.6, math.pi / 2),
        "bookshelf_2": Pose(4.0, 3.6, math.pi / 2),
        "bed": Pose(4.0, 5.0, math.pi / 2),
    }
    g = grid(wall)
    route = g.route(Pose(2.0, 3.0), [_point_region(g, (6.0, 3.0))])
    assert route is not None and route.length > 4.0 + 0.3
    samples = np.concatenate([np.linspace(a, b, 50) for a, b in pairwise(route.points)])
    assert clearance(Room(), g.footprints, samples).min() >= 0.18 - 1e-9


def test_regions_are_visited_in_order():
    objects = {"lamp": Pose(1.0, 1.0), "plant": Pose(7.0, 1.0)}
    g = grid(objects)
    route = g.route(Pose(4.0, 1.0, 0.0), [g.region("plant", 0.5), g.region("lamp", 0.5)])
    first, second = route.points[route.reached[0]], route.points[route.reached[1]]
    assert math.dist(first, (7.0, 1.0)) <= 0.25 + 0.5 + 0.08 and math.dist(second, (1.0, 1.0)) <= 0.25 + 0.5 + 0.08
    # Exact up to the grid: each leg ends at a cell centre inside its region, up to a cell beyond its edge,
    # which the next leg pays again.
    exact = (7.0 - 0.75 - 4.0) + (7.0 - 0.75) - (1.0 + 0.75)
    assert exact <= route.length <= exact + 3 * g.resolution + 0.01
    assert hausdorff(route.points, route.points) == 0.0


def test_no_route_to_an_enclosed_region():
    corner = {"bookshelf": Pose(1.2, 0.5, math.pi / 2), "bookshelf_2": Pose(0.5, 1.2)}  # fence off a corner
    g = grid(corner)
    pocket = _point_region(g, (0.5, 0.5))
    assert pocket.any() and g.route(Pose(6.0, 4.0), [pocket]) is None
    assert g.route(Pose(2.0, 3.0), []) is None


def _point_region(g: Grid, xy: tuple[float, float]) -> np.ndarray:
    """The free cells within 0.3 m of a point."""
    return g.free & (np.linalg.norm(g.centers - np.array(xy), axis=-1) <= 0.3)
