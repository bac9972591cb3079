"""`TabletopPointerPolicy`: find the objects in the image, read which to push where, and move the effector.

Training (`forward`) supervises each part with the simulator's privileged targets (`observation.privileged.*`):
object positions, the pushed object, the goal's anchor objects, offset and keep-away distance, and the oracle's
action. At evaluation the policy sees only the camera image, the effector state and the instruction.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import torch
from lerobot.policies import PreTrainedPolicy
from torch import Tensor
from torch.nn import functional as F  # noqa: N812

from lerobot_policy_tabletop_pointer.configuration_tabletop_pointer import (
    ACTION_KEY,
    IMAGE_KEY,
    PRIVILEGED_PREFIX,
    STATE_KEY,
    TabletopPointerConfig,
)
from lerobot_policy_tabletop_pointer.network import (
    InstructionEncoder,
    ObjectHeatmaps,
    SteeringHead,
    apply_homography,
    pad_rows,
    soft_argmax,
)
from lerobot_policy_tabletop_pointer.vocabulary import Tokenizer, build_vocabulary


def resize_image(image: Tensor, height: int, width: int) -> Tensor:
    """(B, 3, H, W) float image -> (B, 3, height, width), averaging pixels (the same op the training data used)."""
    if image.shape[-2:] == (height, width):
        return image
    return F.interpolate(image, size=(height, width), mode="area")


def nearest_blocks(positions: Tensor, present: Tensor, source: Tensor, effector: Tensor, n: int) -> Tensor:
    """(B, n, 2) positions of the n present blocks nearest the effector, other than the pushed one (weights `source`)."""
    distance = (positions - effector.unsqueeze(1)).norm(dim=-1) + (1 - present) * 10 + source * 10
    index = distance.topk(n, largest=False).indices
    return positions.gather(1, index.unsqueeze(-1).expand(-1, -1, 2))


# Batch sizes below which a row would round otherwise than in a larger batch (measured on AVX2): oneDNN convolves a
# single image's dilated layers in another order, MKL multiplies fewer than 4 rows in another; and the most rows
# `lane_step` runs at once, as oneDNN convolves 16 or more images in another order again.
CONTEXT_ROWS, MATMUL_ROWS, LANE_CHUNK = 2, 4, 8


class Pointed(NamedTuple):
    """What the instruction points at: weights over the objects for the pushed one, its position, and the goal."""

    weights: Tensor
    source: Tensor
    goal: Tensor


def _privileged(batch: dict[str, Any], name: str) -> Tensor:
    return batch[PRIVILEGED_PREFIX + name].float()


class TabletopPointerPolicy(PreTrainedPolicy):
    config_class = TabletopPointerConfig
    name = "tabletop_pointer"

    def __init__(self, config: TabletopPointerConfig, dataset_meta: Any = None, **kwargs: Any) -> None:
        super().__init__(config)
        if not config.vocabulary and dataset_meta is not None:
            config.vocabulary = build_vocabulary(dataset_meta.tasks.index)
        self.config = config
        self.tokenizer = Tokenizer(config.vocabulary, config.max_words)
        n = len(config.objects)
        self.heatmaps = ObjectHeatmaps(n, config.channels)
        self.instruction = InstructionEncoder(self.tokenizer.size, n, config.word_dim, config.text_dim)
        self.steering = SteeringHead(config.head_hidden, config.heading_bins, config.obstacles)
        matrix = torch.tensor(config.image_to_board, dtype=torch.float32)
        self.register_buffer("image_to_board", matrix, persistent=False)
        self.register_buffer("board_to_image", torch.linalg.inv(matrix), persistent=False)
        self.reset()

    def get_optim_params(self) -> dict:
        return self.parameters()

    def reset(self) -> None:
        """A new episode: the goal is read again from its first frame."""
        self._goal: Tensor | None = None
        self._read: tuple[tuple[str, ...], dict[str, Tensor]] | None = None  # the episode's instruction, encoded

    def perceive(self, batch: dict[str, Any]) -> dict[str, Tensor]:
        """Object positions (B, K, 2) in metres, heatmap logits, presence logits and the instruction's heads."""
        image = resize_image(batch[IMAGE_KEY].float(), self.config.image_height, self.config.image_width)
        logits, presence = self.heatmaps(image)
        positions = apply_homography(self.image_to_board, soft_argmax(logits))
        return {
            "logits": logits,
            "presence": presence,
            "positions": positions,
            **self.read(batch["task"], image.device),
        }

    def read(self, tasks: list[str], device: torch.device) -> dict[str, Tensor]:
        """The instruction heads; at evaluation an episode's instruction is encoded once."""
        if self.training:
            return self.instruction(self.tokenizer(list(tasks), device))
        if self._read is None or self._read[0] != tuple(tasks):
            self._read = (tuple(tasks), self.instruction(self.tokenizer(list(tasks), device)))
        return self._read[1]

    def compose(self, seen: dict[str, Tensor]) -> Pointed:
        """The pushed object (its weights over the objects, its position) and the goal, from what `perceive` found."""
        present = torch.sigmoid(seen["presence"])
        positions = seen["positions"]
        source_weights = (seen["source"] + torch.log(present + 1e-6)).softmax(-1)
        source = (source_weights.unsqueeze(-1) * positions).sum(1)
        anchors = torch.cat([positions, torch.zeros_like(positions[:, :1])], dim=1)
        anchor_logits = seen["anchor"] + torch.log(F.pad(present, (0, 1), value=1.0) + 1e-6)
        distance = (positions - source.unsqueeze(1)).norm(dim=-1)
        near = present * torch.sigmoid((self.config.neighbour_radius - distance) / 0.005) * (1 - source_weights)
        near = F.pad(near / near.sum(-1, keepdim=True).clamp(min=1e-6), (0, 1))
        group = torch.sigmoid(seen["group"]).unsqueeze(-1)
        weights = (1 - group) * anchor_logits.softmax(-1) + group * near
        anchor = (weights.unsqueeze(-1) * anchors).sum(1)
        away = source - anchor
        away = away / away.norm(dim=-1, keepdim=True).clamp(min=1e-6)
        return Pointed(source_weights, source, anchor + seen["offset"] + seen["away"].unsqueeze(-1) * away)

    @torch.no_grad()
    def select_action(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        seen = self.perceive(batch)
        pointed = self.compose(seen)
        if self._goal is None or self._goal.shape != pointed.goal.shape:
            self._goal = pointed.goal
        effector = batch[STATE_KEY][:, 2:4].float()
        present = (seen["presence"] > 0).float()
        obstacles = nearest_blocks(seen["positions"], present, pointed.weights, effector, self.config.obstacles)
        action = self.steering.action(*self.steering(effector, pointed.source, self._goal, obstacles))
        return (action * self.config.max_action).clamp(-self.config.max_action, self.config.max_action)

    @torch.no_grad()
    def lane_step(self, batch: dict[str, Any], memories: list[dict[str, Tensor]]) -> Tensor:
        """One control step of independent episodes (evaluation lanes): row i's episode memory is `memories[i]`,
        empty at its episode's start and filled here. A row's action does not depend on its batch: each instruction is
        encoded on its own, the networks run on at most LANE_CHUNK rows at a time, and the layers that round a small
        batch otherwise on AVX2 run on CONTEXT_ROWS or MATMUL_ROWS rows (the last row repeated), which makes it the
        same to the last bit there and costs one lane little. Other CPUs' kernels may round some batch sizes
        otherwise in the last bits (docs/speed.md)."""
        for memory, task in zip(memories, batch["task"], strict=True):
            if "text" not in memory:
                memory["text"] = self.instruction(self.tokenizer([task], batch[STATE_KEY].device))
        tensors = {key: value for key, value in batch.items() if isinstance(value, Tensor)}
        tensors[IMAGE_KEY] = resize_image(tensors[IMAGE_KEY].float(), self.config.image_height, self.config.image_width)
        # On a GPU the kernels are chosen by batch size, so every call runs on the same number of rows there.
        rows = LANE_CHUNK if batch[STATE_KEY].device.type != "cpu" else 1
        actions = []
        for start in range(0, len(memories), LANE_CHUNK):
            chunk = {key: pad_rows(value[start : start + LANE_CHUNK], rows) for key, value in tensors.items()}
            actions.append(self._lane_chunk(chunk, memories[start : start + LANE_CHUNK], rows))
        return torch.cat(actions)

    def _lane_chunk(self, batch: dict[str, Tensor], memories: list[dict[str, Tensor]], rows: int) -> Tensor:
        logits, presence = self.heatmaps(batch[IMAGE_KEY], context_rows=CONTEXT_ROWS)
        text = {key: pad_rows(torch.cat([m["text"][key] for m in memories]), rows) for key in memories[0]["text"]}
        positions = apply_homography(self.image_to_board, soft_argmax(logits))
        seen = {"logits": logits, "presence": presence, "positions": positions, **text}
        pointed = self.compose(seen)
        for i, memory in enumerate(memories):
            memory.setdefault("goal", pointed.goal[i : i + 1])
        goal = pad_rows(torch.cat([m["goal"] for m in memories]), rows)
        effector = batch[STATE_KEY][:, 2:4].float()
        present = (presence > 0).float()
        obstacles = nearest_blocks(positions, present, pointed.weights, effector, self.config.obstacles)
        steer = [pad_rows(value, MATMUL_ROWS) for value in (effector, pointed.source, goal, obstacles)]
        action = self.steering.action(*self.steering(*steer))[: len(memories)]
        return (action * self.config.max_action).clamp(-self.config.max_action, self.config.max_action)

    def predict_action_chunk(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        return self.select_action(batch).unsqueeze(1)

    def forward(self, batch: dict[str, Any]) -> tuple[Tensor, dict]:
        seen = self.perceive(batch)
        with torch.no_grad():
            pointed = self.compose(seen)
        goal_error = (pointed.goal - _privileged(batch, "goal_xy")).norm(dim=-1).mean()
        losses = {**self._perception_losses(batch, seen), **self._instruction_losses(batch, seen)}
        losses["action"] = self._action_loss(batch, pointed.source)
        loss = sum(losses.values())
        return loss, {**{k: v.item() for k, v in losses.items()}, "goal_error_m": goal_error.item()}

    def _perception_losses(self, batch: dict[str, Any], seen: dict[str, Tensor]) -> dict[str, Tensor]:
        logits = seen["logits"]
        b, k, h, w = logits.shape
        truth = _privileged(batch, "objects_xy").view(b, k, 2)
        present = _privileged(batch, "objects_present") > 0.5
        uv = apply_homography(self.board_to_image, truth)
        col = (uv[..., 0] * w).long().clamp(0, w - 1)
        row = (uv[..., 1] * h).long().clamp(0, h - 1)
        cell = row * w + col
        heatmap = F.cross_entropy(logits.flatten(2)[present], cell[present])
        position = (seen["positions"] - truth).norm(dim=-1)[present].mean() * 10
        presence = F.binary_cross_entropy_with_logits(seen["presence"], present.float())
        return {"heatmap": heatmap, "position": position, "presence": presence}

    def _instruction_losses(self, batch: dict[str, Any], seen: dict[str, Tensor]) -> dict[str, Tensor]:
        group = _privileged(batch, "group").view(-1)
        named = group < 0.5
        anchor = -(_privileged(batch, "anchor") * seen["anchor"].log_softmax(-1)).sum(-1)
        offset = ((seen["offset"] - _privileged(batch, "offset")) / 0.1).pow(2).sum(-1)
        away = ((seen["away"] - _privileged(batch, "away").view(-1)) / 0.1).pow(2)
        return {
            "source": F.cross_entropy(seen["source"], _privileged(batch, "source").argmax(-1)),
            "anchor": (anchor * named).sum() / named.sum().clamp(min=1),
            "group": F.binary_cross_entropy_with_logits(seen["group"], group),
            "offset": offset.mean() + away.mean(),
        }

    def _action_loss(self, batch: dict[str, Any], source_seen: Tensor) -> Tensor:
        """The steering head learns from true positions (with noise) and, at `predicted_input_rate`, the predicted
        pushed-object position, so it neither depends on perfect perception nor learns from early garbage alone."""
        b = source_seen.shape[0]
        truth = _privileged(batch, "objects_xy").view(b, -1, 2)
        source_true = (_privileged(batch, "source").unsqueeze(-1) * truth).sum(1)
        use_seen = torch.rand(b, 1, device=truth.device) < self.config.predicted_input_rate
        noise = self.config.position_noise
        source = torch.where(use_seen, source_seen, source_true + noise * torch.randn_like(source_true))
        goal = _privileged(batch, "goal_xy") + noise * torch.randn_like(source_true)
        effector = batch[STATE_KEY][:, 2:4].float()
        present = _privileged(batch, "objects_present")
        noisy = truth + noise * torch.randn_like(truth)
        obstacles = nearest_blocks(noisy, present, _privileged(batch, "source"), effector, self.config.obstacles)
        logits, speed = self.steering(effector, source, goal, obstacles)
        target = batch[ACTION_KEY].float() / self.config.max_action
        moving = (target.norm(dim=-1) > 1e-3).float()
        heading = F.cross_entropy(logits, self.steering.heading_bin(target), reduction="none")
        return (heading * moving).sum() / moving.sum().clamp(min=1) + F.mse_loss(speed, target.norm(dim=-1)) * 10
