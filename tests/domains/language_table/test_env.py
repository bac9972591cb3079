"""LanguageTableEnv: the benchmark's observation/action interface, exact resets, success, registration."""

import importlib
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import LanguageTableTask
from lerobot_contrast.domains.language_table.env import LanguageTableEnv


def sampled(family: str, seed: int = 0) -> Instance:
    return LanguageTableTask(families=(family,)).sample(1, np.random.default_rng(seed))[0]


def near_goal() -> Instance:
    """block2block with the red moon 6 cm from the blue cube and the effector right behind it."""
    scene = Scene(
        objects={"red_moon": Pose(0.35, 0.0, 0.0), "blue_cube": Pose(0.41, 0.0, 0.0)},
        robot=Pose(0.31, 0.0),
    )
    goal = {"block": "red_moon", "target_block": "blue_cube"}
    return Instance("near", "block2block", "push the red moon to the blue cube", scene, goal)


@pytest.mark.parametrize("obs_type", ["rgb", "state"])
def test_observation_matches_the_benchmark(obs_type):
    env = LanguageTableEnv(obs_type=obs_type)
    obs, _ = env.reset(options={"instance": sampled("block2block")})
    expected = {
        "effector_translation": ((2,), np.float32),
        "effector_target_translation": ((2,), np.float32),
        "instruction": ((512,), np.int32),
    }
    if obs_type == "rgb":
        expected["rgb"] = ((180, 320, 3), np.uint8)
    assert {k: (v.shape, v.dtype) for k, v in obs.items()} == expected
    assert env.observation_space.contains(obs)
    assert env.action_space == gym.spaces.Box(-0.1, 0.1, (2,), np.float32)


def test_instruction_is_zero_padded_utf8():
    env = LanguageTableEnv(obs_type="state")
    instance = sampled("separate")
    obs, _ = env.reset(options={"instance": instance})
    data = obs["instruction"]
    assert bytes(data[data > 0].astype(np.uint8)).decode() == instance.instruction
    assert not data[len(instance.instruction.encode()) :].any()
    assert env.task == env.task_description == instance.instruction


def test_reset_places_the_scene_exactly():
    env = LanguageTableEnv(obs_type="state")
    instance = sampled("block2blockrelativelocation")
    obs, _ = env.reset(options={"instance": instance})
    scene = env.scene()
    assert scene.objects == instance.scene.objects
    assert (scene.robot.x, scene.robot.y) == (instance.scene.robot.x, instance.scene.robot.y)
    assert np.array_equal(obs["effector_target_translation"], obs["effector_translation"])
    assert env.instance is instance


def test_is_success_on_reset_and_step_and_termination():
    env = LanguageTableEnv(obs_type="state")
    _, info = env.reset(options={"instance": near_goal()})
    assert info == {"is_success": False}
    for _ in range(3):
        _, reward, terminated, truncated, info = env.step(np.array([0.03, 0.0], np.float32))
        if terminated:
            break
    assert terminated and not truncated
    assert reward == 1.0 and info["is_success"] is True


def test_render_returns_the_observed_frame():
    env = LanguageTableEnv(obs_type="rgb", render_mode="rgb_array")
    obs, _ = env.reset(options={"instance": sampled("block2absolutelocation")})
    obs, *_ = env.step(np.array([0.02, -0.01], np.float32))
    assert np.array_equal(env.render(), obs["rgb"])
    assert obs["rgb"].std() > 10  # a picture, not a blank frame


def test_reset_without_instance_samples_the_family_from_the_seed():
    env = LanguageTableEnv(obs_type="state", family="separate")
    env.reset(seed=3)
    first = env.instance
    env.reset(seed=3)
    assert first.family == "separate"
    assert env.instance.to_json() == first.to_json()


def test_registered_with_gymnasium():
    from lerobot_contrast.domains.language_table import env as module

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # registering twice would warn about overriding
        importlib.reload(module)
    env = gym.make(module.LANGUAGE_TABLE_ID, obs_type="state")
    assert env.spec.max_episode_steps == 200
    assert env.unwrapped._max_episode_steps == 200
    obs, info = env.reset(seed=0)
    assert "rgb" not in obs and "is_success" in info
    _, _, _, _, info = env.step(env.action_space.sample())
    assert "is_success" in info


def test_a_fresh_interpreter_makes_the_env_from_its_module_qualified_id():
    code = (
        "import gymnasium; env = gymnasium.make('lerobot_contrast.domains.language_table.env:lerobot_contrast/LanguageTable-v0');"
        "print(sorted(env.reset(seed=0)[0]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["['effector_target_translation',", "'effector_translation',", "'instruction',", "'rgb']"]


def test_bad_arguments_get_one_line_errors():
    with pytest.raises(ValueError, match="obs_type"):
        LanguageTableEnv(obs_type="pixels")
    with pytest.raises(ValueError, match="render_mode"):
        LanguageTableEnv(render_mode="human")
