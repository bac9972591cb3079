"""A checkpoint of the released architecture at other widths, heads and depths (a lab's own smaller LAVA) converts,
loads through LeRobot's factories and computes what its Flax network computes."""

from __future__ import annotations

import json
from dataclasses import dataclass

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import torch
from flax import traverse_util
from lerobot.configs import PreTrainedConfig
from lerobot.policies import get_policy_class, make_pre_post_processors
from lerobot_policy_language_table.convert import main

from . import flax_reference as ref
from .synthetic_checkpoint import FULL_CLIP, _is_shape, _random_leaf, train_state, write_checkpoint
from .test_lt_convert import INSTRUCTION, _flax_action, _frames, _torch_action


@dataclass(frozen=True)
class Widths:
    """The sizes `SequenceLAVMSE` is built with upstream; the defaults are the released checkpoint's."""

    resnet_width: int = 64
    resnet_stages: tuple[int, ...] = (3, 4)
    pyramid_channels: tuple[int, int] = (128, 256)
    d_model: int = 128
    fusion_heads: int = 2
    fusion_layers: int = 4
    num_heads: int = 2
    temporal_layers: int = 2
    dense_resnet_width: int = 1024
    dense_resnet_blocks: int = 2
    clip: tuple[int, int, int, int] = FULL_CLIP  # width, heads, layers, embedding size


SMALL = Widths(16, (1, 2), (24, 32), 32, 4, 1, 1, 3, 64, 1, (32, 2, 1, 48))


class MultiscaleResNet(nn.Module):
    width: int
    stages: tuple[int, ...]

    @nn.compact
    def __call__(self, x):
        x = nn.Conv(self.width, (7, 7), (2, 2), use_bias=False, name="init_conv")(x)
        x = nn.relu(nn.BatchNorm(use_running_average=True, momentum=0.9, name="init_bn")(x))
        stem = nn.max_pool(x, (3, 3), strides=(2, 2), padding="SAME")
        x = stem
        for k, blocks in enumerate(self.stages):  # computed, never read, as released
            x = ref.ResNetStage(blocks, self.width * 2**k, 1 if k == 0 else 2, name=f"stage{k + 1}")(x)
        return stem


class ResNetVisualEncoder(nn.Module):
    w: Widths

    @nn.compact
    def __call__(self, rgb):
        x = (rgb - ref.RESNET_MEAN) / ref.RESNET_STD
        x = jax.image.resize(x, (x.shape[0], 224, 224, 3), method="bilinear", antialias=False)
        x = MultiscaleResNet(self.w.resnet_width, self.w.resnet_stages)(x)
        pyramid = []
        for channels in self.w.pyramid_channels:
            x = nn.max_pool(nn.relu(nn.Conv(channels, (3, 3))(x)), (2, 2), strides=(2, 2), padding="VALID")
            pyramid.append(x)
        return [*pyramid, nn.max_pool(x, (2, 2), strides=(2, 2), padding="VALID")]


class TemporalTransformer(nn.Module):
    w: Widths

    @nn.compact
    def __call__(self, x):
        d = self.w.d_model
        x = nn.Dense(d)(x) * jnp.sqrt(d) + ref.pos_encoding_1d(x.shape[1], d)[None]
        for _ in range(self.w.temporal_layers):
            x = ref.PrenormEncoderLayer(self.w.num_heads)(x)
        return nn.LayerNorm()(jnp.mean(x, axis=1))


class Encoder(nn.Module):
    w: Widths

    @nn.compact
    def __call__(self, rgb, tokens):
        b, t = rgb.shape[:2]
        pixels = ref.VisualDescriptorsNet(self.w.d_model)(
            ResNetVisualEncoder(self.w)(rgb.reshape(b * t, *rgb.shape[2:]))
        )
        lang = ref.TextEncoder(*self.w.clip)(tokens)
        lang = jnp.repeat(lang / jnp.linalg.norm(lang, axis=-1, keepdims=True), t, axis=0)
        x = (nn.Dense(self.w.d_model)(lang) * jnp.sqrt(self.w.d_model))[:, None]
        for _ in range(self.w.fusion_layers):
            x = ref.PrenormPixelLangEncoder(self.w.fusion_heads)(pixels, x)
        return TemporalTransformer(self.w)(nn.LayerNorm()(x[:, 0]).reshape(b, t, -1))


class ResnetDenseBlock(nn.Module):
    width: int

    @nn.compact
    def __call__(self, x):
        y = nn.Dense(self.width // 4)(nn.relu(x))
        y = nn.Dense(self.width // 4)(nn.relu(y))
        return x + nn.Dense(self.width)(nn.relu(y))


class DenseResnet(nn.Module):
    width: int
    blocks: int

    @nn.compact
    def __call__(self, x):
        x = nn.Dense(self.width)(x)
        for _ in range(self.blocks):
            x = ResnetDenseBlock(self.width)(x)
        return x


class SequenceLAVMSE(nn.Module):
    """`flax_reference.SequenceLAVMSE` with every size a field, as upstream's `SequenceLAVMSE` has them."""

    w: Widths

    @nn.compact
    def __call__(self, rgb, tokens):
        x = Encoder(self.w, name="encoder")(rgb, tokens)
        x = DenseResnet(self.w.dense_resnet_width, self.w.dense_resnet_blocks, name="dense_resnet")(x)
        return nn.Dense(2, name="action_projection")(x)


def _shapes(model: nn.Module) -> dict:
    rgb, tokens = jnp.zeros((1, 4, 180, 320, 3)), jnp.zeros((1, 77), jnp.int32)
    shapes = jax.eval_shape(model.init, jax.random.PRNGKey(0), rgb, tokens)
    return traverse_util.flatten_dict(jax.tree_util.tree_map(lambda s: s.shape, shapes, is_leaf=_is_shape))


def _random_variables(model: nn.Module, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return traverse_util.unflatten_dict({p: _random_leaf(p, shape, rng) for p, shape in _shapes(model).items()})


def test_the_reference_at_released_widths_has_the_released_parameter_tree():
    assert _shapes(SequenceLAVMSE(Widths())) == _shapes(ref.SequenceLAVMSE(FULL_CLIP))


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """A small-width checkpoint in the released format, converted with the CLI."""
    variables = _random_variables(SequenceLAVMSE(SMALL), seed=5)
    root = tmp_path_factory.mktemp("small_lava")
    checkpoint = write_checkpoint(root / "bc_resnet_sim_checkpoint_955000", train_state(variables))
    assert main([str(checkpoint), str(root / "out")]) == 0
    return variables, root / "out"


def test_every_width_the_checkpoint_determines_is_in_the_config(small):
    config = json.loads((small[1] / "config.json").read_text())
    sizes = {k: config[k] for k in ("resnet_width", "pyramid_channels", "d_model", "fusion_heads", "fusion_layers")}
    sizes |= {k: config[k] for k in ("num_heads", "temporal_layers", "dense_resnet_width", "dense_resnet_blocks")}
    assert sizes == {
        "resnet_width": 16, "pyramid_channels": [24, 32], "d_model": 32, "fusion_heads": 4, "fusion_layers": 1,
        "num_heads": 1, "temporal_layers": 3, "dense_resnet_width": 64, "dense_resnet_blocks": 1,
    }  # fmt: skip
    clip = [config[f"clip_{k}"] for k in ("width", "heads", "layers", "embed_dim")]
    assert tuple(clip) == SMALL.clip
    assert "released architecture at other sizes: `clip_width=32`" in (small[1] / "README.md").read_text()


def test_small_lava_loads_through_lerobots_factories_and_matches_flax(small):
    variables, out = small
    config = PreTrainedConfig.from_pretrained(out)
    policy = get_policy_class(config.type).from_pretrained(out)
    pre, post = make_pre_post_processors(config, pretrained_path=str(out))
    action = post(policy.select_action(pre({"observation.images.top": torch.rand(3, 180, 320), "task": INSTRUCTION})))
    assert action.shape == (1, 2) and float(action.abs().max()) <= 0.1
    frames = _frames(4)
    np.testing.assert_allclose(
        _torch_action(policy, frames, INSTRUCTION), _flax_action(SequenceLAVMSE(SMALL), variables, frames, INSTRUCTION),
        atol=1e-4, rtol=1e-4,
    )  # fmt: skip
