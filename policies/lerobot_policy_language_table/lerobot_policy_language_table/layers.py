"""PyTorch layers that compute what their Flax counterparts in the released network compute.

Flax 'SAME' padding (asymmetric at stride 2), Flax attention (queries scaled before the dot product, masked logits
set to the dtype's minimum), the fixed sin/cos position encodings, and the benchmark's image resizes.
"""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)


def same_padding(size: int, kernel: int, stride: int) -> tuple[int, int]:
    """Flax/XLA 'SAME' padding of one spatial axis: the odd pixel goes after, unlike PyTorch's symmetric padding."""
    out = -(-size // stride)
    total = max((out - 1) * stride + kernel - size, 0)
    return total // 2, total - total // 2


def _pad_same(x: torch.Tensor, kernel: tuple[int, int], stride: tuple[int, int], value: float) -> torch.Tensor:
    top, bottom = same_padding(x.shape[-2], kernel[0], stride[0])
    left, right = same_padding(x.shape[-1], kernel[1], stride[1])
    return F.pad(x, (left, right, top, bottom), value=value)


class SameConv2d(nn.Conv2d):
    """`nn.Conv2d` with Flax 'SAME' padding computed from each input's size."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self._conv_forward(_pad_same(x, self.kernel_size, self.stride, 0.0), self.weight, self.bias)


def max_pool_same(x: torch.Tensor, kernel: int, stride: int) -> torch.Tensor:
    """`flax.linen.max_pool(..., padding='SAME')`: padded cells never win the max."""
    x = _pad_same(x, (kernel, kernel), (stride, stride), float("-inf"))
    return F.max_pool2d(x, kernel, stride)


class Attention(nn.Module):
    """`flax.linen.MultiHeadDotProductAttention` at inference: separate query/key/value/out projections."""

    def __init__(self, dim: int, num_heads: int) -> None:
        super().__init__()
        self.num_heads = num_heads
        self.query, self.key, self.value, self.out = (nn.Linear(dim, dim) for _ in range(4))

    def _heads(self, x: torch.Tensor) -> torch.Tensor:
        b, n, d = x.shape
        return x.view(b, n, self.num_heads, d // self.num_heads).transpose(1, 2)

    def forward(self, q_in: torch.Tensor, kv_in: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
        q = self._heads(self.query(q_in))
        q = q / math.sqrt(q.shape[-1])
        logits = q @ self._heads(self.key(kv_in)).transpose(-1, -2)
        if mask is not None:
            # Flax fills masked logits with the dtype's minimum, so a fully masked row stays finite (uniform).
            logits = logits.masked_fill(~mask, torch.finfo(logits.dtype).min)
        out = logits.softmax(dim=-1) @ self._heads(self.value(kv_in))
        b, _, n, _ = out.shape
        return self.out(out.transpose(1, 2).reshape(b, n, -1))


def positional_encoding_1d(length: int, d_model: int) -> torch.Tensor:
    """(length, d_model) sin/cos encoding: even channels sin, odd channels cos."""
    position = np.arange(length)[:, None]
    div = np.exp(np.arange(0, d_model, 2) * -(np.log(1.0e4) / d_model))
    pe = np.zeros((length, d_model), dtype=np.float32)
    pe[:, 0::2] = np.sin(position * div)
    pe[:, 1::2] = np.cos(position * div)
    return torch.from_numpy(pe)


def positional_encoding_2d(d_model: int, height: int, width: int) -> torch.Tensor:
    """(height*width, d_model) encoding exactly as released: built channels-first, then *reshaped* (not transposed).

    The reshape scrambles which channel and position each value belongs to; the network was trained with it.
    """
    half = d_model // 2
    div = np.exp(np.arange(0.0, half, 2) * -(np.log(10000.0) / half))
    sin_w, cos_w = np.sin(np.arange(width)[:, None] * div).T, np.cos(np.arange(width)[:, None] * div).T
    sin_h, cos_h = np.sin(np.arange(height)[:, None] * div).T, np.cos(np.arange(height)[:, None] * div).T
    pe = np.zeros((d_model, height, width))
    pe[0:half:2] = sin_w[:, None, :]
    pe[1:half:2] = cos_w[:, None, :]
    pe[half::2] = sin_h[:, :, None]
    pe[half + 1 :: 2] = cos_h[:, :, None]
    return torch.from_numpy(pe.reshape(height * width, d_model).astype(np.float32))


def resize_bilinear(images: torch.Tensor, height: int, width: int) -> torch.Tensor:
    """Half-pixel-centre bilinear resize without antialiasing, as `jax.image.resize` and `tf.image.resize` do."""
    return F.interpolate(images, size=(height, width), mode="bilinear", align_corners=False, antialias=False)


def center_crop_resize(images: torch.Tensor, factor: float) -> torch.Tensor:
    """The benchmark's evaluation crop: the centre `factor` of the frame, resized back to the frame's size.

    Sizes and offsets are computed in float32 and truncated, as the benchmark's TensorFlow wrapper does
    (180x320 -> 171x304 at offset (4, 8)).
    """
    height, width = images.shape[-2:]
    scaled_h, scaled_w = np.float32(height) * np.float32(factor), np.float32(width) * np.float32(factor)
    top, left = int((np.float32(height) - scaled_h) // 2), int((np.float32(width) - scaled_w) // 2)
    crop = images[..., top : top + int(scaled_h), left : left + int(scaled_w)]
    return resize_bilinear(crop, height, width)


def normalize_imagenet(images: torch.Tensor) -> torch.Tensor:
    mean = images.new_tensor(IMAGENET_MEAN).view(1, 3, 1, 1)
    std = images.new_tensor(IMAGENET_STD).view(1, 3, 1, 1)
    return (images - mean) / std
