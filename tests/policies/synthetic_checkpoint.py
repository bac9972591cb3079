"""Synthetic checkpoints in the released format: the Flax reference's parameter tree, random values, written with
`flax.serialization` like `flax.training.checkpoints` writes a `TrainState` (step, params, opt_state, batch_stats,
norm_info)."""

from __future__ import annotations

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from flax import serialization, traverse_util

from .flax_reference import SequenceLAVMSE

FULL_CLIP = (512, 8, 12, 512)  # CLIP ViT-B/16 text tower: width, heads, layers, embedding size
SMALL_CLIP = (64, 2, 2, 64)
ACTION_MEAN = np.array([0.0012, -0.0031], dtype=np.float32)
ACTION_STD = np.array([0.012, 0.018], dtype=np.float32)


def _random_leaf(path: tuple[str, ...], shape: tuple[int, ...], rng: np.random.Generator) -> np.ndarray:
    leaf = path[-1]
    if leaf == "kernel":
        fan_in = shape[0] * (shape[1] if path[-2] == "out" else 1) if len(shape) == 3 else np.prod(shape[:-1])
        value = rng.normal(0.0, 1.0 / np.sqrt(fan_in), shape)
    elif leaf == "scale":
        value = 1.0 + 0.1 * rng.normal(size=shape)
    elif leaf == "var":
        value = rng.uniform(0.5, 1.5, shape)
    elif leaf in ("embedding", "positional_embedding"):
        value = 0.02 * rng.normal(size=shape)
    else:  # bias, mean
        value = 0.1 * rng.normal(size=shape)
    return value.astype(np.float32)


def random_variables(clip: tuple[int, int, int, int], seed: int = 0) -> dict:
    """{"params", "batch_stats"} of the reference network with random values; shapes come from Flax's own init."""
    model = SequenceLAVMSE(clip)
    rgb, tokens = jnp.zeros((1, 4, 180, 320, 3)), jnp.zeros((1, 77), jnp.int32)
    shapes = jax.eval_shape(model.init, jax.random.PRNGKey(0), rgb, tokens)
    rng = np.random.default_rng(seed)
    flat = traverse_util.flatten_dict(jax.tree_util.tree_map(lambda s: s.shape, shapes, is_leaf=_is_shape))
    return traverse_util.unflatten_dict({path: _random_leaf(path, shape, rng) for path, shape in flat.items()})


def _is_shape(x) -> bool:
    return isinstance(x, jax.ShapeDtypeStruct)


def train_state(variables: dict) -> dict:
    """A state dict shaped like the released `TrainState` (the optimiser state abridged to one moment)."""
    first_kernel = variables["params"]["action_projection"]["kernel"]
    return {
        "step": np.int64(955000),
        "params": variables["params"],
        "opt_state": {"0": {"count": np.int32(955000), "mu": {"action_projection": {"kernel": first_kernel * 0}}}},
        "batch_stats": variables["batch_stats"],
        "norm_info": {
            "observation_statistics": {"effector_translation": {"mean": np.zeros(2), "std": np.ones(2), "n": 32}},
            "action_statistics": {"mean": ACTION_MEAN, "std": ACTION_STD, "n": np.int64(32)},
            "action_min": np.full(2, -0.1, np.float32),
            "action_max": np.full(2, 0.1, np.float32),
        },
    }


def write_checkpoint(path: Path, state: dict) -> Path:
    path.write_bytes(serialization.msgpack_serialize(state))
    return path
