"""The tabletop renderer: camera projection against the benchmark's measured values, and what ends up in frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import board, shapes
from lerobot_contrast.domains.language_table.render import TabletopRenderer

EFFECTOR = (0.3, -0.1)


@pytest.fixture(scope="module")
def renderer() -> TabletopRenderer:
    return TabletopRenderer()


def pixel(renderer: TabletopRenderer, image: np.ndarray, xyz: tuple[float, float, float]) -> tuple[int, ...]:
    col, row = renderer.project(np.array([xyz]))[0]
    return tuple(int(v) for v in image[int(row), int(col)])


def test_projection_matches_measured_benchmark_values(renderer):
    world = [(0.15, -0.3048, 0), (0.15, 0.3048, 0), (0.6, -0.3048, 0), (0.6, 0.3048, 0), (0.375, 0, 0)]
    measured = [(56.6, 25), (263.4, 25), (1, 180), (319, 180), (160, 86)]
    np.testing.assert_allclose(renderer.project(np.array(world)), measured, atol=1.5)


def test_output_shape_and_dtype():
    image = TabletopRenderer(90, 160).render({"red_moon": (0.4, 0.0, 0.0)}, EFFECTOR)
    assert image.shape == (90, 160, 3) and image.dtype == np.uint8


def test_board_and_block_top_colours(renderer):
    image = renderer.render({"blue_cube": (0.4, 0.1, 0.3)}, EFFECTOR)
    assert pixel(renderer, image, (0.4, 0.1, board.BLOCK_HEIGHT)) == board.COLOR_RGB["blue"]
    assert pixel(renderer, image, (0.4, -0.15, 0.0)) == board.BOARD_RGB


@pytest.mark.parametrize("name", board.BLOCK_MODES["BLOCK_8"])
def test_every_block_shows_its_colour(renderer, name):
    image = renderer.render({name: (0.35, 0.05, 1.0)}, EFFECTOR)
    colors = {tuple(c) for c in image.reshape(-1, 3).tolist()}
    assert board.COLOR_RGB[name.split("_")[0]] in colors


def test_yaw_changes_the_image(renderer):
    straight = renderer.render({"green_star": (0.4, 0.0, 0.0)}, EFFECTOR)
    turned = renderer.render({"green_star": (0.4, 0.0, math.pi / 4)}, EFFECTOR)
    assert not np.array_equal(straight, turned)


def test_effector_appears_at_its_projected_position(renderer):
    image = renderer.render({}, (0.45, 0.12))
    r, g, b = pixel(renderer, image, (0.45 + board.EFFECTOR_RADIUS, 0.12, 0.05))
    assert min(r, g, b) > 120 and max(r, g, b) - min(r, g, b) < 10
    assert pixel(renderer, renderer.render({}, None), (0.45, 0.12, 0.0)) == board.BOARD_RGB


def test_nearer_block_hides_the_effector_base(renderer):
    front = (0.35 + board.EFFECTOR_RADIUS, 0.0, 0.01)
    alone = renderer.render({}, (0.35, 0.0))
    behind = renderer.render({"blue_cube": (0.35 + board.EFFECTOR_RADIUS + 0.005 + 0.0199, 0.0, 0.0)}, (0.35, 0.0))
    assert pixel(renderer, behind, front) != pixel(renderer, alone, front)
    r, g, b = pixel(renderer, behind, front)
    assert b > r + 50 and b > g + 50


def test_parked_and_far_blocks_are_invisible(renderer):
    empty = renderer.render({}, EFFECTOR)
    parked = {"red_moon": (5.0, 5.0, 0.0), "blue_cube": (0.375, 3.0, 1.0), "green_star": (-2.0, 0.0, 0.0)}
    assert np.array_equal(renderer.render(parked, EFFECTOR), empty)


def test_rendering_is_deterministic(renderer):
    blocks = {name: (0.25 + 0.03 * i, -0.2 + 0.05 * i, 0.7 * i) for i, name in enumerate(board.BLOCK_MODES["BLOCK_8"])}
    first = renderer.render(blocks, EFFECTOR)
    assert np.array_equal(first, renderer.render(blocks, EFFECTOR))
    assert np.array_equal(first, TabletopRenderer().render(blocks, EFFECTOR))


def test_scene_and_pose_inputs_match_tuples(renderer):
    scene = Scene(objects={"yellow_pentagon": Pose(0.4, 0.1, 0.5)}, robot=Pose(*EFFECTOR))
    expected = renderer.render({"yellow_pentagon": (0.4, 0.1, 0.5)}, EFFECTOR)
    assert np.array_equal(renderer.render_scene(scene), expected)
    assert np.array_equal(renderer.render(scene), expected)


def test_unknown_object_is_a_clear_error(renderer):
    with pytest.raises(ValueError, match="'chair'"):
        renderer.render({"chair": (0.4, 0.0, 0.0)}, EFFECTOR)


@pytest.mark.parametrize("shape", board.SHAPES)
def test_outlines_fit_their_footprint_counter_clockwise(shape):
    points = shapes.outline(shape)
    np.testing.assert_allclose(points.max(axis=0) - points.min(axis=0), board.SHAPE_FOOTPRINT[shape], rtol=1e-9)
    x, y = points.T
    assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
