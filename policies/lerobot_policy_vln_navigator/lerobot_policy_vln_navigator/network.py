"""The navigator's learned parts: a column scanner over the camera image, an instruction reader, an action head."""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn

# Goal features fed to the action head: (dx, dy) in the robot frame and the distance (all / GOAL_SCALE_M),
# the bearing's cosine and sine, and whether the goal has been seen at all.
GOAL_FEATURES = 6
GOAL_SCALE_M = 4.0


def column_bearings(columns: int, hfov_deg: float) -> Tensor:
    """Bearing (radians, left positive) of each scan column's centre for a pinhole camera."""
    focal = (columns / 2) / math.tan(math.radians(hfov_deg) / 2)
    u = torch.arange(columns, dtype=torch.float32) + 0.5
    return torch.atan((columns / 2 - u) / focal)


def goal_features(dx: Tensor, dy: Tensor, known: Tensor) -> Tensor:
    """(B, GOAL_FEATURES) from a goal at (dx, dy) metres in the robot frame (x ahead, y left); zeros if unknown."""
    distance = torch.sqrt(dx**2 + dy**2).clamp(min=1e-6)
    features = torch.stack(
        [dx / GOAL_SCALE_M, dy / GOAL_SCALE_M, distance / GOAL_SCALE_M, dx / distance, dy / distance], -1
    )
    return torch.cat([features * known.unsqueeze(-1), known.unsqueeze(-1)], -1)


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

    def forward(self, image: Tensor) -> tuple[Tensor, Tensor]:
        x = self.convs(image)
        b, c, h, w = x.shape
        x = x.reshape(b, c * h, w)
        x = nn.functional.adaptive_avg_pool1d(x, self.columns)
        x = self.mix(x)
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


class ActionHead(nn.Module):
    """(goal features, which subgoal, range scan, bumper) -> logits over the four commands."""

    def __init__(self, columns: int, hidden: int, commands: int) -> None:
        super().__init__()
        self.net = nn.Sequential(
            nn.Linear(GOAL_FEATURES + 2 + columns, hidden),
            nn.ReLU(),
            nn.Linear(hidden, hidden),
            nn.ReLU(),
            nn.Linear(hidden, commands),
        )

    def forward(self, goal: Tensor, final: Tensor, scan: Tensor, bumper: Tensor) -> Tensor:
        return self.net(torch.cat([goal, final.unsqueeze(-1), scan, bumper.unsqueeze(-1)], -1))
