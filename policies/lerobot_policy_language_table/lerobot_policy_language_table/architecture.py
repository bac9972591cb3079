"""The sizes of a LAVA network (widths, attention heads, depths) read from its checkpoint's parameter shapes."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from lerobot_policy_language_table.flax_checkpoint import DAMAGED, CheckpointError

ENCODER = "params/encoder"
TEXT = f"{ENCODER}/TextEncoder_0"
RESNET = f"{ENCODER}/ResNetVisualEncoder_0"
FUSION = f"{ENCODER}/PrenormPixelLangEncoder_"
TEMPORAL = f"{ENCODER}/TemporalTransformer_0/PrenormEncoderLayer_"
QUERY = "MultiHeadDotProductAttention_0/query/kernel"


def entry(flat: dict[str, np.ndarray], path: str) -> np.ndarray:
    if path not in flat:
        raise CheckpointError(f"the checkpoint has no {path!r}: is it the Language-Table BC checkpoint?")
    return flat[path]


def dims(flat: dict[str, np.ndarray], path: str, ndim: int) -> tuple[int, ...]:
    """The shape of entry `path`, which must exist and have `ndim` dimensions."""
    shape = entry(flat, path).shape
    if len(shape) != ndim:
        raise CheckpointError(f"{path} has shape {shape}, not {ndim}-D: {DAMAGED}")
    return shape


def count(flat: dict[str, np.ndarray], prefix: str) -> int:
    """How many modules `{prefix}0`, `{prefix}1`, ... the checkpoint holds (the converter reports gaps)."""
    indices = {m.group(1) for p in flat if (m := re.match(rf"{re.escape(prefix)}(\d+)/", p))}
    return len(indices)


def _heads(flat: dict[str, np.ndarray], prefix: str, layers: int, query: str) -> int | None:
    """The attention heads of a stack of layers (query kernels are (in, heads, head_dim)); None for an empty stack."""
    found = {dims(flat, f"{prefix}{k}/{query}", 3)[1] for k in range(layers)}
    if len(found) > 1:
        raise CheckpointError(f"the layers {prefix}* differ in attention heads {sorted(found)}; one count is supported")
    return found.pop() if found else None


def _known(sizes: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in sizes.items() if v is not None}


def text_tower_size(flat: dict[str, np.ndarray]) -> dict[str, int]:
    """The CLIP text tower's size (the released one is ViT-B/16's: 512 wide, 12 layers, 8 heads)."""
    vocab, width = dims(flat, f"{TEXT}/token_embedding/embedding", 2)
    layers = count(flat, f"{TEXT}/transformer/resblocks.")
    return _known(
        {
            "clip_vocab_size": vocab,
            "clip_width": width,
            "clip_heads": _heads(flat, f"{TEXT}/transformer/resblocks.", layers, "attn/query/kernel"),
            "clip_layers": layers,
            "clip_context_length": dims(flat, f"{TEXT}/positional_embedding", 2)[0],
            "clip_embed_dim": dims(flat, f"{TEXT}/text_projection/kernel", 2)[1],
        }
    )


def network_sizes(flat: dict[str, np.ndarray]) -> dict[str, Any]:
    """Every `LanguageTableConfig` size the checkpoint determines; sizes of empty stacks keep their defaults."""
    d_model = dims(flat, f"{ENCODER}/Dense_0/kernel", 2)[1]
    if d_model % 4:
        raise CheckpointError(f"{ENCODER}/Dense_0/kernel gives d_model {d_model}, not a multiple of 4 as LAVA needs")
    outputs = dims(flat, "params/action_projection/kernel", 2)[1]
    if outputs != 2:
        raise CheckpointError(f"params/action_projection/kernel gives {outputs}-D actions; Language-Table's are 2-D")
    fusion_layers, temporal_layers = count(flat, FUSION), count(flat, TEMPORAL)
    return text_tower_size(flat) | _known(
        {
            "resnet_width": dims(flat, f"{RESNET}/MultiscaleResNet_0/init_conv/kernel", 4)[3],
            "pyramid_channels": tuple(dims(flat, f"{RESNET}/Conv_{k}/kernel", 4)[3] for k in range(2)),
            "d_model": d_model,
            "fusion_heads": _heads(flat, FUSION, fusion_layers, QUERY),
            "num_heads": _heads(flat, TEMPORAL, temporal_layers, QUERY),
            "fusion_layers": fusion_layers,
            "temporal_layers": temporal_layers,
            "dense_resnet_width": dims(flat, "params/dense_resnet/Dense_0/kernel", 2)[1],
            "dense_resnet_blocks": count(flat, "params/dense_resnet/ResnetDenseBlock_"),
        }
    )


def resnet_stage_sizes(flat: dict[str, np.ndarray]) -> tuple[int, ...]:
    """Bottleneck blocks per ResNet stage (released: (3, 4))."""
    stages = count(flat, f"{RESNET}/MultiscaleResNet_0/stage")
    return tuple(count(flat, f"{RESNET}/MultiscaleResNet_0/stage{s}/block") for s in range(1, stages + 1))
