"""A converted checkpoint drives the Language-Table simulator through LeRobot's processors, as an evaluation would."""

from __future__ import annotations

import gymnasium
import numpy as np
import torch
from lerobot.policies import make_pre_post_processors
from lerobot.policies.utils import prepare_observation_for_inference
from lerobot_policy_language_table import LanguageTablePolicy

import lerobot_contrast.domains.language_table.env  # noqa: F401  (registers the env id)
from lerobot_contrast.domains.language_table.physics import clip_target


def test_converted_policy_drives_the_simulator(converted):
    policy = LanguageTablePolicy.from_pretrained(converted)
    pre, post = make_pre_post_processors(policy.config, pretrained_path=str(converted))
    env = gymnasium.make("lerobot_contrast/LanguageTable-v0", obs_type="rgb")
    obs, _ = env.reset(seed=0)
    policy.reset()
    for _ in range(5):
        observation = prepare_observation_for_inference(
            {"observation.images.top": obs["rgb"]}, torch.device("cpu"), task=env.unwrapped.task
        )
        action = post(policy.select_action(pre(observation)))[0].numpy()
        assert action.shape == (2,) and np.all(np.abs(action) <= 0.1)
        target = obs["effector_target_translation"]
        obs, *_ = env.step(action)
        # The simulator moved its effector target by exactly the policy's action (clipped to the workspace).
        np.testing.assert_allclose(obs["effector_target_translation"], clip_target(*(target + action)), atol=1e-6)
    env.close()
