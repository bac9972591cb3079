"""Per-column obstacle ranges from an aligned depth image: the pixels that are neither floor nor ceiling, placed
with the camera's pinhole model (field of view, image size, mounting height)."""

from __future__ import annotations

import math

import torch
from torch import Tensor


def depth_ranges(
    depth: Tensor,
    hfov_deg: float,
    mount_height_m: float,
    columns: int,
    band_m: tuple[float, float],
    max_range_m: float,
    rows: int = 96,
) -> Tensor:
    """(B, 1, H, W) optical-axis depth in metres -> (B, columns) horizontal range to the nearest obstacle per column
    strip (`max_range_m` where none). A pixel is an obstacle when the point it sees stands between the heights `band_m`
    (lower is floor, higher is ceiling); zero depth is a sensor's "no reading". Pixels are subsampled, not averaged,
    to about `rows` rows, so no depth edge blends into a point between the two surfaces."""
    h, w = depth.shape[-2:]
    step = max(1, h // rows)
    d = depth[:, 0, ::step, ::step].float()
    focal = (w / 2) / math.tan(math.radians(hfov_deg) / 2)
    v = torch.arange(0, h, step, dtype=torch.float32, device=d.device) + 0.5
    u = torch.arange(0, w, step, dtype=torch.float32, device=d.device) + 0.5
    up = (h / 2 - v) / focal
    left = (w / 2 - u) / focal
    height = mount_height_m + d * up[:, None]  # depth along the optical axis times the ray's rise per unit depth
    horizontal = d * torch.sqrt(1 + left**2)[None, :]
    obstacle = (d > 0.05) & (height > band_m[0]) & (height < band_m[1])
    nearest = torch.where(obstacle, horizontal, torch.full_like(horizontal, max_range_m)).amin(dim=1)  # (B, W')
    strip = (u * columns / w).long().clamp(max=columns - 1)
    out = torch.full((d.shape[0], columns), max_range_m, device=d.device)
    return out.scatter_reduce(1, strip.expand_as(nearest), nearest, reduce="amin").clamp(max=max_range_m)
