"""The ray-cast RGB-D camera and the top-down map."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment import CATALOG, CameraSpec, Footprints, RayCaster, Room, render_map

SPEC = CameraSpec(width=160, height=120, hfov_deg=69.0, mount_height=0.55)


def test_depth_is_the_distance_along_the_optical_axis_to_the_wall_and_floor():
    rgb, depth = RayCaster(SPEC).render(Room(), Footprints.from_objects({}), Pose(2.0, 3.0, 0.0))
    assert rgb.shape == (120, 160, 3) and rgb.dtype == np.uint8 and depth.shape == (120, 160)
    # The wall at x = 8 is 6 m ahead: every pixel that sees it has depth 6 (a plane facing the camera); the
    # outer columns see the side walls, nearer.
    assert np.abs(depth[59:61, 40:120] - 6.0).max() < 1e-3 and depth[60, 0] < 6.0
    # The floor in the bottom row: depth = height / tan(angle below the axis).
    focal = 80 / math.tan(math.radians(34.5))
    assert depth[119, 80] == pytest.approx(0.55 * focal / 59.5, rel=1e-3)


def test_furniture_occludes_what_is_behind_it_with_its_own_colour():
    bookshelf = Footprints.from_objects({"bookshelf": Pose(4.0, 3.0, math.pi / 2)})  # 0.35 m deep along x
    rgb, depth = RayCaster(SPEC).render(Room(), bookshelf, Pose(2.0, 3.0, 0.0))
    assert depth[60, 80] == pytest.approx(4.0 - 0.175 - 2.0, abs=1e-3)
    colour = np.array(CATALOG["bookshelf"].color)
    assert np.abs(rgb[60, 80] / np.linalg.norm(rgb[60, 80]) - colour / np.linalg.norm(colour)).max() < 0.02
    # 1 m wide at 1.825 m: it spans 2 * atan(0.5 / 1.825) of the 69 degree field of view.
    seen = int((np.abs(depth[60] - depth[60, 80]) < 1e-2).sum())
    assert seen == pytest.approx(160 * math.tan(math.atan(0.5 / 1.825)) / math.tan(math.radians(34.5)), abs=2)


def test_a_low_object_shows_its_top_to_a_higher_camera():
    bed = Footprints.from_objects({"bed": Pose(4.0, 3.0, 0.0)})  # 0.55 m high, from x = 3 to 5
    high = CameraSpec(width=160, height=120, hfov_deg=69.0, mount_height=1.2)
    rgb, depth = RayCaster(high).render(Room(), bed, Pose(1.5, 3.0, 0.0))
    column, colours = depth[60:, 80], rgb[60:, 80].astype(float)
    face = np.isclose(column, 1.5, atol=1e-3)
    top = (column > 1.5 + 1e-3) & (column < 3.5)  # beyond the front face, before the back edge
    assert face.any() and top.any()
    bed_colour = np.array(CATALOG["bed"].color) / np.linalg.norm(CATALOG["bed"].color)
    for rgb_seen in colours[face | top]:
        assert np.abs(rgb_seen / np.linalg.norm(rgb_seen) - bed_colour).max() < 0.03


def test_a_narrower_field_of_view_magnifies():
    bookshelf = Footprints.from_objects({"bookshelf": Pose(4.0, 3.0, math.pi / 2)})
    widths = []
    for hfov in (90.0, 45.0):
        _, depth = RayCaster(CameraSpec(160, 120, hfov)).render(Room(), bookshelf, Pose(2.0, 3.0, 0.0))
        widths.append(int((np.abs(depth[60] - depth[60, 80]) < 1e-2).sum()))
    assert widths[1] / widths[0] == pytest.approx(math.tan(math.radians(45)) / math.tan(math.radians(22.5)), rel=0.1)
    with pytest.raises(ValueError, match="field of view"):
        RayCaster(CameraSpec(hfov_deg=180.0))


def test_the_map_shows_furniture_robot_and_paths_to_scale():
    footprints = Footprints.from_objects({"couch": Pose(2.0, 2.0)})
    image = render_map(Room(), footprints, Pose(6.0, 4.0, 0.0), path=[(6.0, 4.0), (6.0, 1.0)], px_per_m=50)
    assert image.shape == (6 * 50 + 20, 8 * 50 + 20, 3)
    assert tuple(image[10 + 300 - 100, 10 + 140]) == CATALOG["couch"].color  # (2.8, 2.0) is on the couch, +y up
    assert tuple(image[10 + 300 - 125, 10 + 300]) == (220, 40, 40)  # on the path, red
