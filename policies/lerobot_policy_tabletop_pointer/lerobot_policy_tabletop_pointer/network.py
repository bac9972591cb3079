"""The networks: object heatmaps from pixels, an instruction encoder with pointer heads, and the action MLP."""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn
from torch.nn import functional as F  # noqa: N812


def _conv(c_in: int, c_out: int, stride: int = 1, dilation: int = 1) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(c_in, c_out, 3, stride=stride, padding=dilation, dilation=dilation),
        nn.GroupNorm(4, c_out),
        nn.ReLU(inplace=True),
    )


class ObjectHeatmaps(nn.Module):
    """(B, 3, H, W) image in [0, 1] -> (B, K, H/2, W/2) heatmap logits, one per object, and (B, K) presence logits.

    Two coordinate channels let the net tell the board's near and far rows apart; dilated layers at quarter
    resolution see whole blocks, and a skip from half resolution keeps the heatmaps sharp.
    """

    def __init__(self, n_objects: int, channels: int) -> None:
        super().__init__()
        c = channels
        self.stem = nn.Sequential(_conv(5, c // 2, stride=2), _conv(c // 2, c))
        self.context = nn.Sequential(_conv(c, c, stride=2), _conv(c, c, dilation=2), _conv(c, c, dilation=4))
        self.head = nn.Sequential(nn.Conv2d(2 * c, c, 1), nn.ReLU(inplace=True), nn.Conv2d(c, n_objects, 1))
        self.presence = nn.Linear(2, 1)

    def forward(self, image: Tensor, context_rows: int = 1) -> tuple[Tensor, Tensor]:
        """`context_rows`: the dilated layers run on at least this many images (the last one repeated), for a
        batch whose rows must round as in any larger batch: oneDNN convolves a single image's dilated layers in
        another order."""
        b, _, h, w = image.shape
        v = torch.linspace(-1, 1, h, device=image.device).view(1, 1, h, 1).expand(b, 1, h, w)
        u = torch.linspace(-1, 1, w, device=image.device).view(1, 1, 1, w).expand(b, 1, h, w)
        fine = self.stem(torch.cat([image * 2 - 1, u, v], dim=1))
        coarse = F.interpolate(self.context(pad_rows(fine, context_rows))[:b], size=fine.shape[-2:], mode="nearest")
        logits = self.head(torch.cat([fine, coarse], dim=1))
        flat = logits.flatten(2)
        pooled = torch.stack([flat.amax(-1), flat.logsumexp(-1) - flat.mean(-1)], dim=-1)
        return logits, self.presence(pooled).squeeze(-1)


def pad_rows(value: Tensor, rows: int) -> Tensor:
    """`value` with its last row repeated up to `rows` rows."""
    missing = rows - value.shape[0]
    return value if missing <= 0 else torch.cat([value, value[-1:].expand(missing, *value.shape[1:])])


def soft_argmax(logits: Tensor) -> Tensor:
    """(B, K, h, w) logits -> (B, K, 2) expected (u, v) in [0, 1] (cell centres) under each map's softmax."""
    b, k, h, w = logits.shape
    probs = logits.flatten(2).softmax(-1).view(b, k, h, w)
    u = (torch.arange(w, device=logits.device, dtype=logits.dtype) + 0.5) / w
    v = (torch.arange(h, device=logits.device, dtype=logits.dtype) + 0.5) / h
    return torch.stack([(probs.sum(2) * u).sum(-1), (probs.sum(3) * v).sum(-1)], dim=-1)


def apply_homography(matrix: Tensor, points: Tensor) -> Tensor:
    """(3, 3) homography applied to (..., 2) points."""
    ones = torch.ones_like(points[..., :1])
    mapped = torch.cat([points, ones], dim=-1) @ matrix.T
    return mapped[..., :2] / mapped[..., 2:]


class InstructionEncoder(nn.Module):
    """Word ids (B, L) -> what the instruction asks: which object to push, which objects (or the board origin) the
    goal is measured from, an offset, a distance to keep away, and whether the goal is "its neighbours".
    """

    def __init__(self, vocabulary_size: int, n_objects: int, word_dim: int, text_dim: int) -> None:
        super().__init__()
        self.embed = nn.Embedding(vocabulary_size, word_dim, padding_idx=0)
        self.gru = nn.GRU(word_dim, text_dim // 2, batch_first=True, bidirectional=True)
        self.mix = nn.Sequential(nn.Linear(text_dim + word_dim, text_dim), nn.ReLU(inplace=True))
        self.source = nn.Linear(text_dim, n_objects)
        self.anchor = nn.Linear(text_dim, n_objects + 1)
        self.geometry = nn.Linear(text_dim, 4)  # offset x, offset y, away distance, neighbour-group logit

    def forward(self, words: Tensor) -> dict[str, Tensor]:
        mask = (words > 0).float()
        lengths = mask.sum(1).clamp(min=1)
        embedded = self.embed(words)
        packed = nn.utils.rnn.pack_padded_sequence(
            embedded, lengths.long().cpu(), batch_first=True, enforce_sorted=False
        )
        _, hidden = self.gru(packed)
        bag = (embedded * mask.unsqueeze(-1)).sum(1) / lengths.unsqueeze(-1)
        text = self.mix(torch.cat([hidden[0], hidden[1], bag], dim=-1))
        geometry = self.geometry(text)
        return {
            "source": self.source(text),
            "anchor": self.anchor(text),
            "offset": geometry[:, :2] * 0.1,
            "away": geometry[:, 2] * 0.1,
            "group": geometry[:, 3],
        }


class SteeringHead(nn.Module):
    """Effector target, pushed-object, goal and nearby-block positions (metres) -> a heading and a speed.

    The heading is a choice among `bins` directions, not a regressed vector: where the demonstrations go around a
    block on either side, a regressed mean would point into it (or stand still), while the most likely bin picks a side.
    """

    def __init__(self, hidden: int, bins: int, obstacles: int) -> None:
        super().__init__()
        self.bins = bins
        self.net = nn.Sequential(
            nn.Linear(14 + 3 * obstacles, hidden),
            nn.ReLU(inplace=True),
            nn.Linear(hidden, hidden),
            nn.ReLU(inplace=True),
            nn.Linear(hidden, hidden),
            nn.ReLU(inplace=True),
            nn.Linear(hidden, bins + 1),
        )
        angles = torch.arange(bins) * (2 * math.pi / bins)
        self.register_buffer("headings", torch.stack([angles.cos(), angles.sin()], dim=-1), persistent=False)

    def forward(self, effector: Tensor, source: Tensor, goal: Tensor, obstacles: Tensor) -> tuple[Tensor, Tensor]:
        """(heading logits (B, bins), speed (B,) in units of max_action)."""
        to_source, to_goal = source - effector, goal - source
        features = [effector - effector.new_tensor((0.375, 0.0)), to_source, to_goal, goal - effector]
        norms = [to_source.norm(dim=-1, keepdim=True), to_goal.norm(dim=-1, keepdim=True)]
        directions = [to_source / norms[0].clamp(min=1e-3), to_goal / norms[1].clamp(min=1e-3)]
        near = obstacles - effector.unsqueeze(1)
        scaled = [*(f * 10 for f in features), *(n * 10 for n in norms), *directions]
        out = self.net(torch.cat([*scaled, near.flatten(1) * 10, near.norm(dim=-1) * 10], dim=-1))
        return out[:, : self.bins], out[:, self.bins]

    def heading_bin(self, action: Tensor) -> Tensor:
        """The bin of each action's direction."""
        return (action @ self.headings.T).argmax(-1)

    def action(self, logits: Tensor, speed: Tensor) -> Tensor:
        """The most likely bin's heading, refined by its two neighbours' probabilities, times the speed."""
        probs = logits.softmax(-1)
        best = probs.argmax(-1, keepdim=True)
        window = (best + torch.tensor([-1, 0, 1], device=logits.device)) % self.bins
        heading = (probs.gather(1, window).unsqueeze(-1) * self.headings[window]).sum(1)
        heading = heading / heading.norm(dim=-1, keepdim=True).clamp(min=1e-6)
        return heading * speed.clamp(min=0).unsqueeze(-1)
