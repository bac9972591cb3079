"""The navigator's learned parts: a column scanner over the camera image and an instruction reader."""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn


def column_bearings(columns: int, hfov_deg: float) -> Tensor:
    """Bearing (radians, left positive) of each scan column's centre for a pinhole camera."""
    focal = (columns / 2) / math.tan(math.radians(hfov_deg) / 2)
    u = torch.arange(columns, dtype=torch.float32) + 0.5
    return torch.atan((columns / 2 - u) / focal)


class ColumnScanner(nn.Module):
    """(B, 3, H, W) image -> per column: class logits (B, C, K + 1) and log range (B, C)."""

    def __init__(self, classes: int, columns: int, channels: int, image_height: int) -> None:
        super().__init__()
        c = channels
        self.columns = columns
        self.convs = nn.Sequential(
            nn.Conv2d(3, c // 2, 3, stride=2, padding=1),
            nn.ReLU(),
            nn.Conv2d(c // 2, c, 3, stride=(2, 1), padding=1),
            nn.ReLU(),
            nn.Conv2d(c, c, 3, stride=(2, 1), padding=1),
            nn.ReLU(),
            nn.Conv2d(c, c, 3, stride=(2, 1), padding=1),
            nn.ReLU(),
        )
        rows = math.ceil(image_height / 16)
        self.mix = nn.Sequential(
            nn.Conv1d(c * rows, 2 * c, 3, padding=1),
            nn.ReLU(),
            nn.Conv1d(2 * c, 2 * c, 5, padding=2),
            nn.ReLU(),
        )
        self.classes = nn.Conv1d(2 * c, classes, 1)
        self.range = nn.Conv1d(2 * c, 1, 1)

    def features(self, image: Tensor) -> Tensor:
        x = self.convs(image)
        b, c, h, w = x.shape
        x = nn.functional.adaptive_avg_pool1d(x.reshape(b, c * h, w), self.columns)
        return self.mix(x)

    def classify(self, image: Tensor) -> Tensor:
        """Class logits (B, C, K + 1) alone (what `select_action` uses)."""
        return self.classes(self.features(image)).transpose(1, 2)

    def forward(self, image: Tensor) -> tuple[Tensor, Tensor]:
        x = self.features(image)
        return self.classes(x).transpose(1, 2), self.range(x)[:, 0]


class InstructionReader(nn.Module):
    """Word ids (B, T) -> logits over the categories for the first subgoal and for the final one."""

    def __init__(self, vocabulary_size: int, categories: int, word_dim: int, text_dim: int) -> None:
        super().__init__()
        self.embed = nn.Embedding(vocabulary_size, word_dim, padding_idx=0)
        self.gru = nn.GRU(word_dim, text_dim, batch_first=True)
        self.first = nn.Linear(text_dim, categories)
        self.final = nn.Linear(text_dim, categories)

    def forward(self, ids: Tensor) -> tuple[Tensor, Tensor]:
        out, _ = self.gru(self.embed(ids))
        last = out[torch.arange(ids.shape[0]), (ids > 0).sum(1).clamp(min=1) - 1]  # the state after the last word
        return self.first(last), self.final(last)
