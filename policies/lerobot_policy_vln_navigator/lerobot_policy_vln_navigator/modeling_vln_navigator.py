"""`VLNNavigatorPolicy`: scan the camera image for furniture, read which two objects the instruction names, map
obstacles from the depth image and where each object was seen, and plan the next discrete command on that map.

Training (`forward`) supervises the scanner with the simulator's per-column ray hits (class, and range as an
auxiliary target) and the reader with the instance's subgoal categories (`observation.privileged.*`). At evaluation
the policy sees only the RGB and depth images, odometry and the instruction.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
from lerobot.policies import PreTrainedPolicy
from torch import Tensor
from torch.nn import functional as F  # noqa: N812

from lerobot_policy_vln_navigator.configuration_vln_navigator import (
    COMMANDS,
    DEPTH_KEY,
    IMAGE_KEY,
    MISSING_DEPTH,
    PRIVILEGED_PREFIX,
    STATE_KEY,
    VLNNavigatorConfig,
)
from lerobot_policy_vln_navigator.depth import depth_ranges
from lerobot_policy_vln_navigator.memory import SightMemory
from lerobot_policy_vln_navigator.network import ColumnScanner, InstructionReader, column_bearings
from lerobot_policy_vln_navigator.occupancy import OccupancyMap, Planner, frontier_cells, goal_cells
from lerobot_policy_vln_navigator.vocabulary import Tokenizer, build_vocabulary

# Batch sizes within which the scanner rounds a row as in any other (measured on AVX2): oneDNN convolves a single
# image in another order, and 16 or more in another again.
SCAN_ROWS, LANE_CHUNK = 2, 8
FORWARD, TURN_LEFT, TURN_RIGHT, STOP = (COMMANDS.index(c) for c in ("forward", "turn_left", "turn_right", "stop"))


def resize_image(image: Tensor, height: int, width: int) -> Tensor:
    """(B, 3, H, W) float image -> (B, 3, height, width), averaging pixels (the same op the training data used)."""
    if image.shape[-2:] == (height, width):
        return image
    if image.shape[-2] % height == 0 and image.shape[-1] % width == 0:  # the same means, twice as fast
        return F.avg_pool2d(image, (image.shape[-2] // height, image.shape[-1] // width))
    return F.interpolate(image, size=(height, width), mode="area")


def _pad_rows(value: Tensor, rows: int) -> Tensor:
    """`value` with its last row repeated up to `rows` rows."""
    missing = rows - value.shape[0]
    return value if missing <= 0 else torch.cat([value, value[-1:].expand(missing, *value.shape[1:])])


class MissingDepthError(ValueError):
    """The robot gives no aligned depth image."""


def _privileged(batch: dict[str, Any], name: str) -> Tensor:
    return batch[PRIVILEGED_PREFIX + name].float()


class VLNNavigatorPolicy(PreTrainedPolicy):
    config_class = VLNNavigatorConfig
    name = "vln_navigator"

    def __init__(self, config: VLNNavigatorConfig, dataset_meta: Any = None, **kwargs: Any) -> None:
        super().__init__(config)
        if not config.vocabulary and dataset_meta is not None:
            config.vocabulary = build_vocabulary(dataset_meta.tasks.index)
        self.config = config
        self.tokenizer = Tokenizer(config.vocabulary, config.max_words)
        k = len(config.categories)
        self.scanner = ColumnScanner(k + 1, config.columns, config.channels, config.image_height)
        self.reader = InstructionReader(self.tokenizer.size, k, config.word_dim, config.text_dim)
        self.planner = Planner(config.robot_radius_m, config.clearance_m)
        self.register_buffer("bearings", column_bearings(config.columns, config.hfov_deg), persistent=False)
        self.reset()

    def get_optim_params(self) -> dict:
        return self.parameters()

    def reset(self) -> None:
        """A new episode: forget what was seen and which subgoal is next."""
        self._episode: list[dict[str, Any]] | None = None

    def scan(self, batch: dict[str, Any]) -> tuple[Tensor, Tensor]:
        """Per-column class logits (B, C, K + 1) and the learned range head's ranges in metres (B, C), a training
        target that shapes the scanner's features (the map's ranges come from depth)."""
        image = resize_image(batch[IMAGE_KEY].float(), self.config.image_height, self.config.image_width)
        logits, log_range = self.scanner(image)
        return logits, log_range.exp().clamp(max=self.config.max_range_m)

    def obstacle_ranges(self, batch: dict[str, Any]) -> Tensor:
        """(B, C) range to the nearest obstacle per scan column, from the aligned depth image."""
        if DEPTH_KEY not in batch:
            raise MissingDepthError(MISSING_DEPTH)
        c = self.config
        band = (c.obstacle_min_m, c.obstacle_max_m)
        return depth_ranges(batch[DEPTH_KEY], c.hfov_deg, c.camera_height_m, c.columns, band, c.max_range_m)

    def read(self, tasks: list[str], device: torch.device) -> tuple[Tensor, Tensor]:
        return self.reader(self.tokenizer(list(tasks), device))

    def _start_episode(self, tasks: list[str], state: np.ndarray, device: torch.device) -> list[dict[str, Any]]:
        first, final = self.read(tasks, device)
        return [
            {
                "memory": SightMemory(len(self.config.categories), self.config.memory_points),
                "map": OccupancyMap((float(state[i, 0]), float(state[i, 1])), self.config.map_resolution_m),
                "targets": (int(first[i].argmax()), int(final[i].argmax())),
                "phase": 0,
                "searched": 0,
            }
            for i in range(first.shape[0])
        ]

    @torch.no_grad()
    def select_action(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        state = batch[STATE_KEY].float().cpu().numpy().astype(np.float64)
        image = resize_image(batch[IMAGE_KEY].float(), self.config.image_height, self.config.image_width)
        logits = self.scanner.classify(image)
        if self._episode is None or len(self._episode) != state.shape[0]:
            self._episode = self._start_episode(batch["task"], state, logits.device)
        return self._commands(self._episode, state, self.obstacle_ranges(batch), logits)

    @torch.no_grad()
    def lane_step(self, batch: dict[str, Any], memories: list[dict[str, Any]]) -> Tensor:
        """One control step of independent episodes (evaluation lanes): row i's episode is `memories[i]`, empty at
        its start and filled here. A row's command is the same in any batch: each instruction is read on its own and
        the scanner sees each image as in any batch (`lane_logits`)."""
        state = batch[STATE_KEY].float().cpu().numpy().astype(np.float64)
        image = resize_image(batch[IMAGE_KEY].float(), self.config.image_height, self.config.image_width)
        logits = self.lane_logits(image)
        for i, memory in enumerate(memories):
            if not memory:
                memory.update(self._start_episode(batch["task"][i : i + 1], state[i : i + 1], image.device)[0])
        return self._commands(memories, state, self.obstacle_ranges(batch), logits)

    def lane_logits(self, image: Tensor) -> Tensor:
        """The scanner's class logits for lanes' resized images, each row as in any batch (to the last bit on AVX2;
        other CPUs may round some batch sizes otherwise): the scanner runs on SCAN_ROWS to LANE_CHUNK rows at a time,
        the last row repeated (on a GPU, whose kernels are chosen by batch size, always on LANE_CHUNK)."""
        rows = LANE_CHUNK if image.device.type != "cpu" else SCAN_ROWS
        chunks = [image[start : start + LANE_CHUNK] for start in range(0, image.shape[0], LANE_CHUNK)]
        return torch.cat([self.scanner.classify(_pad_rows(chunk, rows))[: len(chunk)] for chunk in chunks])

    def _commands(self, episodes: list[dict[str, Any]], state: np.ndarray, ranges: Tensor, logits: Tensor) -> Tensor:
        """(B, commands) one-hot next commands, each episode's map and memory updated with its row's scan."""
        confidence, classes = (t.numpy() for t in logits.softmax(-1).cpu().max(-1))
        bearings, scans = self.bearings.cpu().numpy().astype(np.float64), ranges.cpu().numpy().astype(np.float64)
        # Up close an object fills the view and the scanner's class is least sure: where a subgoal is comes from
        # sightings at least `near_m` away.
        keep = (classes < len(self.config.categories)) & (confidence >= self.config.seen_confidence)
        keep &= scans >= self.config.near_m
        actions = torch.zeros(state.shape[0], len(COMMANDS))
        for i, episode in enumerate(episodes):
            pose = state[i, :3]
            episode["memory"].add(pose, bearings, scans[i], classes[i], keep[i])
            episode["map"].add_scan(pose, bearings, scans[i], self.config.max_range_m)
            if state[i, 5] > 0.5:
                episode["map"].add_bump(pose, self.config.robot_radius_m + 0.05)
            actions[i, self._command(episode, pose)] = 1.0
        return actions.to(logits.device)

    def _command(self, episode: dict[str, Any], pose: np.ndarray) -> int:
        """The next command for one robot: plan on the map to where the current subgoal was seen (after the first,
        the final one, stopping there); while it is unseen, look around, then explore the map's frontier."""
        grid, targets = episode["map"], episode["targets"]
        window = self.planner.window(grid, pose)
        here = tuple(int(v[0]) - w.start for v, w in zip(grid.cells(pose[None, :2]), window, strict=True))
        if episode["phase"] == 0 and self._reached(episode, window, here, targets[0]):
            episode["phase"] = 1
        if episode["phase"] == 1 and self._reached(episode, window, here, targets[1]):
            return STOP
        goals = self._goals(episode, window, episode["memory"].points(targets[episode["phase"]]))
        if goals is None:
            if episode["searched"] < self.config.search_turns:
                episode["searched"] += 1
                return TURN_LEFT
            goals = frontier_cells(grid, window)
        return self._steer(grid, window, self.planner.field(grid, window, goals), pose)

    def _goals(self, episode: dict[str, Any], window: tuple[slice, slice], points: np.ndarray) -> np.ndarray | None:
        """Cells of `window` within reach of where `points` gather, or None while there are none."""
        goals = goal_cells(episode["map"], window, points, self.config.reach_m) if len(points) else None
        return goals if goals is not None and goals.any() else None

    def _reached(self, episode: dict[str, Any], window: tuple[slice, slice], here: tuple[int, int], k: int) -> bool:
        """Whether the robot is within reach of category `k` as seen from near (far sightings place it too loosely)."""
        goals = self._goals(episode, window, episode["memory"].points(k, self.config.confirm_m))
        return goals is not None and bool(goals[here])

    def _steer(self, grid: OccupancyMap, window: tuple[slice, slice], field: np.ndarray, pose: np.ndarray) -> int:
        """Of the twelve headings a 30-degree turn reaches, the one whose look-ahead point has the lowest cost-to-go:
        forward when it is the current heading (or as good), else turn towards it."""
        headings = pose[2] + np.arange(12) * math.radians(30.0)
        ahead = pose[None, :2] + self.config.lookahead_m * np.stack([np.cos(headings), np.sin(headings)], -1)
        rows, cols = grid.cells(ahead)
        rows, cols = rows - window[0].start, cols - window[1].start
        inside = (rows >= 0) & (rows < field.shape[0]) & (cols >= 0) & (cols < field.shape[1])
        rows, cols = np.clip(rows, 0, field.shape[0] - 1), np.clip(cols, 0, field.shape[1] - 1)
        costs = np.where(inside, field[rows, cols], np.inf)
        best = int(np.argmin(costs))
        if not np.isfinite(costs[best]):
            return TURN_LEFT
        if costs[0] <= costs[best] + 1e-6:
            return FORWARD
        return TURN_LEFT if best <= 6 else TURN_RIGHT

    def predict_action_chunk(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        return self.select_action(batch).unsqueeze(1)

    def forward(self, batch: dict[str, Any]) -> tuple[Tensor, dict]:
        logits, ranges = self.scan(batch)
        first, final = self.read(batch["task"], logits.device)
        truth_class = _privileged(batch, "column_class").long()
        truth_range = _privileged(batch, "column_range").clamp(min=0.05, max=self.config.max_range_m)
        losses = {
            "scan_class": F.cross_entropy(logits.flatten(0, 1), truth_class.flatten()),
            "scan_range": (ranges.clamp(min=0.05).log() - truth_range.log()).abs().mean(),
            "first": F.cross_entropy(first, _privileged(batch, "first").argmax(-1)),
            "final": F.cross_entropy(final, _privileged(batch, "final").argmax(-1)),
        }
        accuracy = (logits.argmax(-1) == truth_class).float().mean()
        return sum(losses.values()), {**{k: v.item() for k, v in losses.items()}, "scan_accuracy": accuracy.item()}
