"""The policy behaves as a LeRobot policy and as the benchmark's evaluation wrappers: found by LeRobot's factories,
4-frame history with the first frame repeated, one CLIP embedding per instruction, de-normalised and clipped actions."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import torch
from lerobot.configs import PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies import get_policy_class, make_policy_config, make_pre_post_processors
from lerobot.policies.utils import prepare_observation_for_inference
from lerobot_policy_language_table import ClipActionProcessorStep, LanguageTableConfig, LanguageTablePolicy
from lerobot_policy_language_table.layers import center_crop_resize
from lerobot_policy_language_table.tokenizer import ClipTokenizer

from .synthetic_checkpoint import ACTION_MEAN, ACTION_STD

IMAGE = "observation.images.top"
TASK = "push the red moon to the top left corner"


@pytest.fixture
def policy(converted) -> LanguageTablePolicy:
    return LanguageTablePolicy.from_pretrained(converted)


def _frame(seed: int) -> torch.Tensor:
    return torch.from_numpy(np.random.default_rng(seed).uniform(size=(1, 3, 180, 320)).astype(np.float32))


def _batch(frame: torch.Tensor, task: str = TASK) -> dict:
    return {IMAGE: frame, "task": [task]}


def _direct(policy: LanguageTablePolicy, frames: list[torch.Tensor], task: str = TASK) -> torch.Tensor:
    """The network run on an explicit history, oldest frame first."""
    x = center_crop_resize(torch.cat(frames), 0.95)[None]
    with torch.no_grad():
        return policy.model(x, policy.text_embedding([task]))


def test_lerobot_factories_build_and_load_the_policy(converted):
    assert get_policy_class("language_table") is LanguageTablePolicy
    config = make_policy_config("language_table", device="cpu")
    assert isinstance(config, LanguageTableConfig) and config.clip_width == 512
    assert config.input_features[IMAGE] == PolicyFeature(FeatureType.VISUAL, (3, 180, 320))
    loaded = PreTrainedConfig.from_pretrained(converted)
    assert loaded.type == "language_table" and loaded.clip_width == 64
    _, post = make_pre_post_processors(loaded, pretrained_path=str(converted))
    assert any(isinstance(step, ClipActionProcessorStep) for step in post.steps)
    _, fresh_post = make_pre_post_processors(config)
    assert any(isinstance(step, ClipActionProcessorStep) for step in fresh_post.steps)


def test_a_plain_interpreter_loads_the_policy_path_through_plugin_discovery(converted):
    code = (
        "import sys, torch\n"
        "from lerobot.utils.import_utils import register_third_party_plugins\n"
        "from lerobot.configs import PreTrainedConfig\n"
        "from lerobot.policies import get_policy_class, make_pre_post_processors\n"
        "register_third_party_plugins()\n"
        "cfg = PreTrainedConfig.from_pretrained(sys.argv[1])\n"
        "policy = get_policy_class(cfg.type).from_pretrained(sys.argv[1])\n"
        "pre, post = make_pre_post_processors(cfg, pretrained_path=sys.argv[1])\n"
        "batch = pre({'observation.images.top': torch.rand(3, 180, 320), 'task': 'push the red moon'})\n"
        "print(type(policy).__name__, tuple(post(policy.select_action(batch)).shape))\n"
    )
    out = subprocess.run([sys.executable, "-c", code, str(converted)], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "LanguageTablePolicy (1, 2)"


def test_postprocessor_denormalises_with_the_checkpoint_statistics_then_clips(converted):
    _, post = make_pre_post_processors(PreTrainedConfig.from_pretrained(converted), pretrained_path=str(converted))
    action = post(torch.tensor([[0.5, -2.0], [40.0, -40.0]]))
    expected_first = ACTION_MEAN + np.array([0.5, -2.0], dtype=np.float32) * ACTION_STD
    np.testing.assert_allclose(action[0].numpy(), expected_first, rtol=1e-6)
    np.testing.assert_allclose(action[1].numpy(), [0.1, -0.1])


def test_robot_observation_runs_through_the_processors(policy, converted):
    pre, post = make_pre_post_processors(policy.config, pretrained_path=str(converted))
    frame = (np.random.default_rng(0).uniform(size=(180, 320, 3)) * 255).astype(np.uint8)
    observation = prepare_observation_for_inference({IMAGE: frame}, torch.device("cpu"), task=TASK)
    batch = pre(observation)
    assert batch["task"] == [TASK] and batch[IMAGE].shape == (1, 3, 180, 320)
    action = post(policy.select_action(batch))
    assert action.shape == (1, 2) and float(action.abs().max()) <= 0.1


def test_history_starts_with_the_first_frame_repeated_and_slides(policy):
    frames = [_frame(k) for k in range(5)]
    actions = [policy.select_action(_batch(f)) for f in frames]
    torch.testing.assert_close(actions[0], _direct(policy, [frames[0]] * 4), atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(actions[3], _direct(policy, frames[:4]), atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(actions[4], _direct(policy, frames[1:5]), atol=1e-5, rtol=1e-5)
    policy.reset()
    torch.testing.assert_close(policy.select_action(_batch(frames[4])), _direct(policy, [frames[4]] * 4))


def test_a_new_instruction_starts_a_new_history(policy):
    frames = [_frame(k) for k in range(3)]
    for frame in frames[:2]:
        policy.select_action(_batch(frame))
    other = "separate the blue cube from the rest of the blocks"
    action = policy.select_action(_batch(frames[2], other))
    torch.testing.assert_close(action, _direct(policy, [frames[2]] * 4, other))


def test_each_instruction_is_embedded_once(policy, monkeypatch):
    calls = []
    embed = policy.model.embed_text
    monkeypatch.setattr(policy.model, "embed_text", lambda tokens: calls.append(len(tokens)) or embed(tokens))
    for _ in range(2):
        policy.reset()
        for k in range(3):
            policy.select_action(_batch(_frame(k)))
    policy.select_action(_batch(_frame(0), "move the green star down"))
    assert calls == [1, 1]


def test_select_action_without_an_instruction_says_what_is_missing(policy):
    with pytest.raises(ValueError, match=r"batch\['task'\]"):
        policy.select_action({IMAGE: _frame(0)})


def test_forward_is_the_bc_loss_and_leaves_clip_frozen(policy):
    policy.train()
    frames = torch.rand(2, 4, 3, 180, 320)
    batch = {IMAGE: frames, "action": torch.zeros(2, 2), "task": [TASK, "push the blue cube right"]}
    loss, info = policy.forward(batch)
    loss.backward()
    assert info["loss"] == pytest.approx(loss.item()) and loss.item() > 0
    assert all(p.grad is None for p in policy.model.text.parameters())
    assert policy.model.lang_proj.weight.grad is not None
    trainable = {id(p) for p in policy.get_optim_params()}
    assert not trainable & {id(p) for p in policy.model.text.parameters()}


def test_clip_tokens_are_zero_padded_to_77():
    tokens = ClipTokenizer()("a photo of a cat")
    assert tokens.shape == (77,) and tokens.dtype == np.int64
    assert tokens[:8].tolist() == [49406, 320, 1125, 539, 320, 2368, 49407, 0] and not tokens[7:].any()
    assert ClipTokenizer()("cat " * 100)[-1] == 2368  # cut at 77 tokens, as the benchmark's tokenizer does


def test_config_rejects_inputs_the_network_cannot_read():
    two_cameras = {
        IMAGE: PolicyFeature(FeatureType.VISUAL, (3, 180, 320)),
        "observation.images.wrist": PolicyFeature(FeatureType.VISUAL, (3, 180, 320)),
    }
    with pytest.raises(ValueError, match="exactly one camera image"):
        LanguageTablePolicy(LanguageTableConfig(device="cpu", input_features=two_cameras))
