"""Where each Flax parameter of the released checkpoint goes in `LanguageTableNet`, and how its layout changes.

Module paths use Flax's auto-names (`Dense_0`, `PrenormPixelLangEncoder_3`, ...). Layouts: Dense kernels (in, out) are
transposed; attention kernels (in, heads, head_dim) / (heads, head_dim, out) are flattened to (in, out) first; conv
kernels go HWIO -> OIHW; LayerNorm/BatchNorm `scale` is the torch `weight`; BatchNorm `mean`/`var` are running stats.
"""

from __future__ import annotations

import re

import numpy as np

_ATTN = r"MultiHeadDotProductAttention_0/(query|key|value|out)"
_FFN = {"Dense_0": "dense_in", "Dense_1": "dense_out"}

# (Flax module path regex, torch module path template); the first match wins.
MODULE_RULES: list[tuple[str, str]] = [
    (r"encoder/ResNetVisualEncoder_0/MultiscaleResNet_0/(init_conv|init_bn)", r"vision.resnet.\1"),
    (r"encoder/ResNetVisualEncoder_0/Conv_(\d+)", r"vision.pyramid_convs.\1"),
    (r"encoder/VisualDescriptorsNet_0/Dense_(\d+)", r"tokens.dense.\1"),
    (r"encoder/TextEncoder_0", "text"),
    (r"encoder/TextEncoder_0/(token_embedding|ln_final|text_projection)", r"text.\1"),
    (r"encoder/TextEncoder_0/transformer/resblocks\.(\d+)/(ln_1|ln_2)", r"text.resblocks.\1.\2"),
    (r"encoder/TextEncoder_0/transformer/resblocks\.(\d+)/attn/(query|key|value|out)", r"text.resblocks.\1.attn.\2"),
    (r"encoder/TextEncoder_0/transformer/resblocks\.(\d+)/mlp/(c_fc|c_proj)", r"text.resblocks.\1.mlp.\2"),
    (r"encoder/Dense_0", "lang_proj"),
    (r"encoder/PrenormPixelLangEncoder_(\d+)/LayerNorm_0", r"fusion.\1.pixel_norm"),
    (r"encoder/PrenormPixelLangEncoder_(\d+)/LayerNorm_1", r"fusion.\1.lang_norm"),
    (rf"encoder/PrenormPixelLangEncoder_(\d+)/{_ATTN}", r"fusion.\1.attn.\2"),
    (r"encoder/PrenormPixelLangEncoder_(\d+)/LayerNorm_2", r"fusion.\1.ffn.norm"),
    *[(rf"encoder/PrenormPixelLangEncoder_(\d+)/{k}", rf"fusion.\1.ffn.{v}") for k, v in _FFN.items()],
    (r"encoder/LayerNorm_0", "fusion_norm"),
    (r"encoder/TemporalTransformer_0/Dense_0", "temporal.dense"),
    (r"encoder/TemporalTransformer_0/PrenormEncoderLayer_(\d+)/LayerNorm_0", r"temporal.layers.\1.norm"),
    (rf"encoder/TemporalTransformer_0/PrenormEncoderLayer_(\d+)/{_ATTN}", r"temporal.layers.\1.attn.\2"),
    (r"encoder/TemporalTransformer_0/PrenormEncoderLayer_(\d+)/LayerNorm_1", r"temporal.layers.\1.ffn.norm"),
    *[
        (rf"encoder/TemporalTransformer_0/PrenormEncoderLayer_(\d+)/{k}", rf"temporal.layers.\1.ffn.{v}")
        for k, v in _FFN.items()
    ],
    (r"encoder/TemporalTransformer_0/LayerNorm_0", "temporal.norm"),
    (r"dense_resnet/Dense_0", "head.dense"),
    (r"dense_resnet/ResnetDenseBlock_(\d+)/Dense_(\d+)", r"head.blocks.\1.dense.\2"),
    (r"action_projection", "action_projection"),
]
_COMPILED = [(re.compile(pattern), template) for pattern, template in MODULE_RULES]

LEAF_NAMES = {
    "kernel": "weight",
    "scale": "weight",
    "bias": "bias",
    "embedding": "weight",
    "mean": "running_mean",
    "var": "running_var",
    "positional_embedding": "positional_embedding",
}

UNUSED_PREFIX = "encoder/ResNetVisualEncoder_0/MultiscaleResNet_0/stage"


def torch_key(flax_path: str) -> str | None:
    """'encoder/Dense_0/kernel' -> 'lang_proj.weight'; None if no rule maps the path."""
    module, _, leaf = flax_path.rpartition("/")
    if leaf not in LEAF_NAMES:
        return None
    for pattern, template in _COMPILED:
        match = pattern.fullmatch(module)
        if match:
            return f"{match.expand(template)}.{LEAF_NAMES[leaf]}"
    return None


def to_torch_layout(flax_path: str, value: np.ndarray) -> np.ndarray:
    """The Flax array rearranged to the layout of its torch parameter."""
    module, _, leaf = flax_path.rpartition("/")
    if leaf == "kernel" and value.ndim == 4:
        return value.transpose(3, 2, 0, 1)
    if leaf == "kernel" and value.ndim == 3:
        flat = value.reshape(-1, value.shape[-1]) if module.endswith("/out") else value.reshape(value.shape[0], -1)
        return flat.T
    if leaf == "kernel":
        return value.T
    if leaf == "bias":
        return value.reshape(-1)
    return value


def _bottleneck_shapes(block: str, c_in: int, filters: int, projection: bool) -> dict[str, tuple[int, ...]]:
    c_out = 4 * filters
    convs = {"conv1": (1, 1, c_in, filters), "conv2": (3, 3, filters, filters), "conv3": (1, 1, filters, c_out)}
    if projection:
        convs["proj_conv"] = (1, 1, c_in, c_out)
    shapes = {f"params/{block}/{name}/kernel": shape for name, shape in convs.items()}
    for name, shape in convs.items():
        bn = f"{block}/{name.replace('conv', 'bn')}"
        for collection, leaves in (("params", ("scale", "bias")), ("batch_stats", ("mean", "var"))):
            shapes.update({f"{collection}/{bn}/{leaf}": (shape[-1],) for leaf in leaves})
    return shapes


def unused_resnet_shapes(width: int, stage_sizes: tuple[int, ...]) -> dict[str, tuple[int, ...]]:
    """Shapes of the ResNet stages' entries: stage i has `stage_sizes[i]` bottlenecks of `width * 2**i` filters
    (released: 3 of 64, then 4 of 128).

    The released network computes these stages but reads no output of theirs, so they are checked, not converted.
    """
    shapes: dict[str, tuple[int, ...]] = {}
    c_in = width
    for stage, blocks in enumerate(stage_sizes, start=1):
        filters = width * 2 ** (stage - 1)
        for k in range(1, blocks + 1):
            block = f"{UNUSED_PREFIX}{stage}/block{k}"
            shapes.update(_bottleneck_shapes(block, c_in, filters, projection=k == 1))
            c_in = 4 * filters
    return shapes
