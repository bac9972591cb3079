"""The `tabletop_pointer` plugin: LeRobot's policy contract, what it may read, and the goals it can express."""

import numpy as np
import pytest
import torch
from lerobot.policies import get_policy_class, make_policy_config
from lerobot_policy_tabletop_pointer import TabletopPointerConfig, TabletopPointerPolicy
from lerobot_policy_tabletop_pointer.configuration_tabletop_pointer import BENCHMARK_IMAGE_TO_BOARD, PRIVILEGED_PREFIX
from lerobot_policy_tabletop_pointer.vocabulary import UNKNOWN, Tokenizer, build_vocabulary

from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.camera import Camera
from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.training import targets
from lerobot_contrast.training.episodes import NoisyOracle, Simulator


def _frames(n_instances: int = 6, seed: int = 0) -> tuple[list[dict], list]:
    task = LanguageTableTask()
    rng = np.random.default_rng(seed)
    instances = task.sample(n_instances, rng)
    frames: list[dict] = []
    simulator = Simulator(task)
    for instance in instances:
        simulator.rollout(instance, NoisyOracle(0.0, rng), max_steps=3, record=frames.append)
    return frames, instances


def _batch(frames: list[dict]) -> dict:
    batch = {"task": [f["task"] for f in frames]}
    for key in frames[0]:
        if key == "task":
            continue
        values = torch.from_numpy(np.stack([f[key] for f in frames]))
        batch[key] = values.permute(0, 3, 1, 2).float() / 255 if key.startswith("observation.images") else values
    return batch


def _policy(vocabulary: list[str]) -> TabletopPointerPolicy:
    return TabletopPointerPolicy(TabletopPointerConfig(device="cpu", vocabulary=vocabulary))


def test_unseen_words_map_to_unknown_and_long_instructions_are_cut():
    tokenizer = Tokenizer(build_vocabulary(["push the red moon", "Push the BLUE cube!"]), max_words=4)
    ids = tokenizer(["push the green moon", "push the red moon to the blue cube"])
    assert ids.shape == (2, 4)
    assert ids[0, 2] == UNKNOWN and ids[0, 3] != UNKNOWN
    assert (ids[1] != 0).all()


def test_policy_type_resolves_through_lerobot_factories():
    assert get_policy_class("tabletop_pointer") is TabletopPointerPolicy
    assert isinstance(make_policy_config("tabletop_pointer"), TabletopPointerConfig)


def test_privileged_targets_are_never_policy_inputs():
    config = TabletopPointerConfig()
    config.input_features = {**config.input_features, PRIVILEGED_PREFIX + "goal_xy": object()}
    config.set_dataset_feature_metadata({})
    assert sorted(config.input_features) == ["observation.images.top", "observation.state"]


def test_forward_returns_a_loss_that_trains_every_part():
    frames, _ = _frames()
    batch = _batch(frames)
    policy = _policy(build_vocabulary(batch["task"]))
    loss, info = policy.forward(batch)
    loss.backward()
    assert torch.isfinite(loss)
    assert {"heatmap", "position", "source", "anchor", "offset", "action", "goal_error_m"} <= set(info)
    for name, module in (("heatmaps", policy.heatmaps), ("text", policy.instruction), ("action", policy.steering)):
        assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in module.parameters()), name


def test_select_action_reads_the_camera_frame_at_any_size_and_keeps_the_goal_for_the_episode():
    frames, _ = _frames(1)
    policy = _policy(build_vocabulary([frames[0]["task"]])).eval()
    full = torch.rand(1, 3, board.IMAGE_HEIGHT, board.IMAGE_WIDTH)
    batch = {"observation.images.top": full, "observation.state": torch.tensor([[0.3, 0.0, 0.3, 0.0]]), "task": ["x"]}
    action = policy.select_action(batch)
    assert action.shape == (1, 2) and action.abs().max() <= policy.config.max_action
    goal = policy._goal.clone()
    policy.select_action({**batch, "observation.images.top": torch.rand_like(full)})
    assert torch.equal(policy._goal, goal)
    policy.reset()
    assert policy._goal is None


def test_benchmark_calibration_maps_image_points_onto_the_board():
    camera = Camera()
    points = np.array([[x, y, board.BLOCK_HEIGHT] for x in (0.2, 0.4, 0.55) for y in (-0.25, 0.0, 0.2)])
    uv = camera.project(points) / (camera.width, camera.height)
    mapped = np.c_[uv, np.ones(len(uv))] @ np.array(BENCHMARK_IMAGE_TO_BOARD).T
    assert np.abs(mapped[:, :2] / mapped[:, 2:] - points[:, :2]).max() < 1e-4


@pytest.mark.parametrize("family", fam.FAMILIES)
def test_the_goal_structure_expresses_every_family_exactly(family):
    """With perfect perception and instruction heads, `compose` gives the oracle's goal: the policy's structure can
    represent every family's goal, so what remains to learn is seeing and reading."""
    task = LanguageTableTask(families=[family])
    policy = _policy([])
    for instance in task.sample(5, np.random.default_rng(3)):
        truth = targets.frame_targets(instance, instance.scene)
        k = targets.K
        big = 40.0
        seen = {
            "positions": torch.from_numpy(truth[PRIVILEGED_PREFIX + "objects_xy"]).view(1, k, 2),
            "presence": torch.from_numpy(truth[PRIVILEGED_PREFIX + "objects_present"] * 2 * big - big)[None],
            "source": torch.from_numpy(truth[PRIVILEGED_PREFIX + "source"] * big)[None],
            "anchor": torch.log(torch.from_numpy(truth[PRIVILEGED_PREFIX + "anchor"]) + 1e-12)[None],
            "offset": torch.from_numpy(truth[PRIVILEGED_PREFIX + "offset"])[None],
            "away": torch.from_numpy(truth[PRIVILEGED_PREFIX + "away"]),
            "group": torch.tensor([big if truth[PRIVILEGED_PREFIX + "group"][0] else -big]),
        }
        goal = policy.compose(seen).goal
        np.testing.assert_allclose(goal[0].numpy(), truth[PRIVILEGED_PREFIX + "goal_xy"], atol=2e-3)
