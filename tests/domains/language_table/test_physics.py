"""TabletopPhysics: exact resets, target clipping, arm tracking, friction, no tunnelling, determinism."""

import math

import numpy as np
import pytest

from lerobot_contrast.domains.language_table.board import SHAPE_FOOTPRINT, WORKSPACE_BOUNDS
from lerobot_contrast.domains.language_table.physics import TabletopPhysics, footprint_hull

BLOCKS = {
    "red_moon": (0.30, -0.10, 0.3),
    "blue_cube": (0.40, 0.12, -1.2),
    "green_star": (0.45, -0.05, 2.5),
    "yellow_pentagon": (0.25, 0.15, 0.0),
}


def make(blocks=BLOCKS, effector=(0.35, 0.0)) -> TabletopPhysics:
    physics = TabletopPhysics()
    physics.set_state(blocks, effector)
    return physics


def test_set_state_reproduces_poses_exactly():
    physics = make()
    physics.step((0.05, 0.05))  # disturb, then reset over it
    physics.set_state(BLOCKS, (0.2345678, -0.1234567))
    blocks, effector = physics.state()
    assert blocks == BLOCKS
    assert effector == (0.2345678, -0.1234567)
    assert physics.target == effector


@pytest.mark.parametrize("shape", sorted(SHAPE_FOOTPRINT))
def test_hull_matches_footprint(shape):
    hull = np.array(footprint_hull(shape))
    assert np.allclose(hull.max(axis=0) - hull.min(axis=0), SHAPE_FOOTPRINT[shape], atol=1e-9)


def test_action_and_target_are_clipped():
    (x_min, y_min), (x_max, y_max) = WORKSPACE_BOUNDS
    physics = make({}, (0.30, 0.0))
    physics.step((1.0, -1.0))  # action clipped to +-0.1
    assert physics.target == pytest.approx((0.40, -0.10))
    for _ in range(5):
        physics.step((0.1, -0.1))
    assert physics.target == (x_max, y_min)
    physics.step((-0.1, 0.1))
    assert physics.target == pytest.approx((x_max - 0.1, y_min + 0.1))


def test_effector_tracks_target_like_the_benchmark_arm():
    physics = make({}, (0.30, 0.0))
    physics.step((0.03, 0.0))
    assert 0.025 <= physics.effector[0] - 0.30 <= 0.031
    physics.step((0.0, 0.0))
    assert physics.effector[0] - 0.30 == pytest.approx(0.030, abs=5e-4)


def test_pushed_block_moves_then_stops():
    physics = make({"blue_cube": (0.40, 0.0, 0.0)}, (0.32, 0.0))
    for _ in range(5):
        physics.step((0.03, 0.0))
    for _ in range(3):
        physics.step((0.0, 0.0))
    x_rest = physics.state()[0]["blue_cube"]
    physics.step((0.0, 0.0))
    assert x_rest[0] > 0.45
    assert physics.state()[0]["blue_cube"] == x_rest


def test_blocks_do_not_tunnel_at_max_action():
    blocks = {"blue_cube": (0.30, 0.0, 0.0), "red_moon": (0.36, 0.0, 0.0)}
    physics = make(blocks, (0.20, 0.0))
    for _ in range(4):
        physics.step((0.1, 0.0))
        poses, (ex, _) = physics.state()
        # The effector stays behind the cube, which stays behind the moon it shoves.
        assert ex < poses["blue_cube"][0] < poses["red_moon"][0]
    assert poses["red_moon"][0] > 0.45


def test_same_state_and_actions_give_identical_trajectories():
    actions = np.random.default_rng(0).uniform(-0.05, 0.05, (60, 2)) + (0.01, 0.0)

    def rollout(physics):
        physics.set_state(BLOCKS, (0.35, 0.0))
        out = []
        for action in actions:
            physics.step(action)
            out.append(physics.state())
        return out

    reused = TabletopPhysics()
    first = rollout(reused)
    assert rollout(reused) == first
    assert rollout(TabletopPhysics()) == first
    assert any(not math.isclose(first[-1][0][n][0], BLOCKS[n][0]) for n in BLOCKS)  # something was pushed
