"""Each layer type of the port computes what Flax's own module computes, with parameters converted by the converter."""

from __future__ import annotations

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import torch
from flax import traverse_util
from lerobot_policy_language_table import layers
from lerobot_policy_language_table.param_map import LEAF_NAMES, to_torch_layout

from .flax_reference import pos_encoding_1d, pos_encoding_2d
from .synthetic_checkpoint import _random_leaf

TOL = 1e-5


def _flax_params(module: nn.Module, *inputs, collections=("params",)) -> dict:
    """Random values in the module's own parameter tree (scales and biases away from their 1 / 0 init)."""
    shapes = jax.eval_shape(module.init, jax.random.PRNGKey(0), *inputs)
    rng = np.random.default_rng(0)
    out = {}
    for collection in collections:
        flat = traverse_util.flatten_dict(jax.tree_util.tree_map(lambda s: s.shape, shapes[collection], is_leaf=_leaf))
        out[collection] = traverse_util.unflatten_dict({p: _random_leaf(p, s, rng) for p, s in flat.items()})
    return out


def _leaf(x) -> bool:
    return isinstance(x, jax.ShapeDtypeStruct)


def _load(torch_module: torch.nn.Module, variables: dict, prefix: str = "") -> None:
    """Load Flax variables with the converter's leaf names and layout functions (`prefix` names the Flax module)."""
    state = {}
    for collection in variables.values():
        for path, value in traverse_util.flatten_dict(collection, sep="/").items():
            module, _, leaf = path.rpartition("/")
            key = f"{module.replace('/', '.')}.{LEAF_NAMES[leaf]}" if module else LEAF_NAMES[leaf]
            state[key] = torch.from_numpy(np.array(to_torch_layout(f"{prefix}{path}", value)))
    missing, unexpected = torch_module.load_state_dict(state, strict=False)
    assert not unexpected and not [k for k in missing if not k.endswith("num_batches_tracked")]


def _nchw(x: np.ndarray) -> torch.Tensor:
    return torch.from_numpy(np.ascontiguousarray(x.transpose(0, 3, 1, 2)))


def _close(torch_out: torch.Tensor, flax_out, nhwc: bool = False) -> None:
    got = torch_out.detach().numpy()
    want = np.asarray(flax_out)
    np.testing.assert_allclose(got.transpose(0, 2, 3, 1) if nhwc else got, want, atol=TOL, rtol=TOL)


@pytest.mark.parametrize(
    ("size", "kernel", "stride", "bias"), [(224, 7, 2, False), (15, 7, 2, False), (56, 3, 1, True), (9, 3, 2, True)]
)
def test_conv_same_padding(size, kernel, stride, bias):
    x = np.random.default_rng(1).normal(size=(2, size, size, 5)).astype(np.float32)
    flax_conv = nn.Conv(8, (kernel, kernel), (stride, stride), padding="SAME", use_bias=bias)
    variables = _flax_params(flax_conv, x)
    conv = layers.SameConv2d(5, 8, kernel, stride=stride, bias=bias)
    _load(conv, variables, prefix="Conv_0/")
    _close(conv(_nchw(x)), flax_conv.apply(variables, x), nhwc=True)


@pytest.mark.parametrize("size", [112, 7])
def test_max_pool_same(size):
    x = np.random.default_rng(2).normal(size=(2, size, size, 3)).astype(np.float32)
    want = nn.max_pool(jnp.asarray(x), (3, 3), strides=(2, 2), padding="SAME")
    _close(layers.max_pool_same(_nchw(x), 3, 2), want, nhwc=True)


def test_dense():
    x = np.random.default_rng(3).normal(size=(4, 7, 24)).astype(np.float32)
    dense = nn.Dense(16)
    variables = _flax_params(dense, x)
    linear = torch.nn.Linear(24, 16)
    _load(linear, variables, prefix="Dense_0/")
    _close(linear(torch.from_numpy(x)), dense.apply(variables, x))


@pytest.mark.parametrize("eps", [1e-6, 1e-5])
def test_layer_norm(eps):
    x = (3.0 + np.random.default_rng(4).normal(size=(4, 9, 32))).astype(np.float32)
    norm = nn.LayerNorm(epsilon=eps)
    variables = _flax_params(norm, x)
    torch_norm = torch.nn.LayerNorm(32, eps=eps)
    _load(torch_norm, variables, prefix="LayerNorm_0/")
    _close(torch_norm(torch.from_numpy(x)), norm.apply(variables, x))


def test_batch_norm_inference():
    x = np.random.default_rng(5).normal(size=(2, 6, 6, 16)).astype(np.float32)
    bn = nn.BatchNorm(use_running_average=True, momentum=0.9)
    variables = _flax_params(bn, x, collections=("params", "batch_stats"))
    torch_bn = torch.nn.BatchNorm2d(16, eps=1e-5).eval()
    _load(torch_bn, variables, prefix="init_bn/")
    _close(torch_bn(_nchw(x)), bn.apply(variables, x), nhwc=True)


def test_cross_attention():
    rng = np.random.default_rng(6)
    query, kv = rng.normal(size=(3, 1, 128)).astype(np.float32), rng.normal(size=(3, 50, 128)).astype(np.float32)
    mha = nn.MultiHeadDotProductAttention(2)
    variables = _flax_params(mha, query, kv)
    attn = layers.Attention(128, 2)
    _load(attn, variables, prefix="MultiHeadDotProductAttention_0/")
    _close(attn(torch.from_numpy(query), torch.from_numpy(kv)), mha.apply(variables, query, kv))


def test_masked_self_attention_as_in_clip():
    tokens = np.array([[49406, 320, 1125, 49407, 0, 0, 0, 0], [49406, 0, 2368, 49407, 0, 0, 0, 0]])
    x = np.random.default_rng(7).normal(size=(2, 8, 32)).astype(np.float32)
    mask = nn.combine_masks(nn.make_attention_mask(tokens > 0, tokens > 0), nn.make_causal_mask(tokens))
    mha = nn.MultiHeadDotProductAttention(4)
    variables = _flax_params(mha, x, x)
    attn = layers.Attention(32, 4)
    _load(attn, variables, prefix="attn/")
    got = attn(torch.from_numpy(x), torch.from_numpy(x), torch.from_numpy(np.asarray(mask, dtype=bool)))
    _close(got, mha.apply(variables, x, x, mask=mask))


@pytest.mark.parametrize(("src", "dst"), [((171, 304), (180, 320)), ((180, 320), (224, 224))])
def test_bilinear_resize_matches_jax(src, dst):
    x = np.random.default_rng(8).uniform(size=(2, *src, 3)).astype(np.float32)
    want = jax.image.resize(x, (2, *dst, 3), method="bilinear", antialias=False)
    _close(layers.resize_bilinear(_nchw(x), *dst), want, nhwc=True)


def test_center_crop_is_the_benchmarks_171x304_window_at_offset_4_8():
    x = np.random.default_rng(9).uniform(size=(1, 180, 320, 3)).astype(np.float32)
    want = jax.image.resize(x[:, 4:175, 8:312], (1, 180, 320, 3), method="bilinear", antialias=False)
    _close(layers.center_crop_resize(_nchw(x), 0.95), want, nhwc=True)


def test_position_encodings_match_the_loop_by_loop_reference():
    np.testing.assert_allclose(layers.positional_encoding_2d(128, 7, 7).numpy(), pos_encoding_2d(128, 7, 7), atol=1e-6)
    np.testing.assert_allclose(layers.positional_encoding_1d(4, 128).numpy(), pos_encoding_1d(4, 128), atol=1e-6)
