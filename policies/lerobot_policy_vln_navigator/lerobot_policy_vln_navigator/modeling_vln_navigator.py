"""`VLNNavigatorPolicy`: scan the camera image for furniture, read which two objects the instruction names, remember
where they were seen, and choose a discrete command.

Training (`forward`) supervises the scanner with the simulator's per-column ray hits, the reader with the instance's
subgoal categories, and the action head with the shortest-path teacher's command given the true goal
(`observation.privileged.*`). At evaluation the policy sees only the camera image, odometry and the instruction.
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.policies import PreTrainedPolicy
from torch import Tensor
from torch.nn import functional as F  # noqa: N812

from lerobot_policy_vln_navigator.configuration_vln_navigator import (
    ACTION_KEY,
    COMMANDS,
    IMAGE_KEY,
    PRIVILEGED_PREFIX,
    STATE_KEY,
    VLNNavigatorConfig,
)
from lerobot_policy_vln_navigator.memory import SightMemory
from lerobot_policy_vln_navigator.network import (
    ActionHead,
    ColumnScanner,
    InstructionReader,
    column_bearings,
    goal_features,
)
from lerobot_policy_vln_navigator.vocabulary import Tokenizer, build_vocabulary

FORWARD, TURN_LEFT, TURN_RIGHT = (COMMANDS.index(c) for c in ("forward", "turn_left", "turn_right"))


def resize_image(image: Tensor, height: int, width: int) -> Tensor:
    """(B, 3, H, W) float image -> (B, 3, height, width), averaging pixels (the same op the training data used)."""
    if image.shape[-2:] == (height, width):
        return image
    if image.shape[-2] % height == 0 and image.shape[-1] % width == 0:  # the same means, twice as fast
        return F.avg_pool2d(image, (image.shape[-2] // height, image.shape[-1] // width))
    return F.interpolate(image, size=(height, width), mode="area")


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
        self.head = ActionHead(config.columns, config.head_hidden, len(COMMANDS))
        self.register_buffer("bearings", column_bearings(config.columns, config.hfov_deg), persistent=False)
        self.reset()

    def get_optim_params(self) -> dict:
        return self.parameters()

    def reset(self) -> None:
        """A new episode: forget what was seen and which subgoal is next."""
        self._episode: list[dict[str, Any]] | None = None

    def scan(self, batch: dict[str, Any]) -> tuple[Tensor, Tensor]:
        """Per-column class logits (B, C, K + 1) and ranges in metres (B, C)."""
        image = resize_image(batch[IMAGE_KEY].float(), self.config.image_height, self.config.image_width)
        logits, log_range = self.scanner(image)
        return logits, log_range.exp().clamp(max=self.config.max_range_m)

    def read(self, tasks: list[str], device: torch.device) -> tuple[Tensor, Tensor]:
        return self.reader(self.tokenizer(list(tasks), device))

    def _start_episode(self, batch: dict[str, Any], device: torch.device) -> list[dict[str, Any]]:
        first, final = self.read(batch["task"], device)
        return [
            {
                "memory": SightMemory(len(self.config.categories), self.config.memory_points),
                "targets": (int(first[i].argmax()), int(final[i].argmax())),
                "phase": 0,
                "searched": 0,
                "explored": 0,
            }
            for i in range(first.shape[0])
        ]

    @torch.no_grad()
    def select_action(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        state = batch[STATE_KEY].float().cpu()
        logits, ranges = self.scan(batch)
        if self._episode is None or len(self._episode) != state.shape[0]:
            self._episode = self._start_episode(batch, logits.device)
        probs = logits.softmax(-1).cpu()
        confidence, classes = probs.max(-1)
        keep = (classes < len(self.config.categories)) & (confidence >= self.config.seen_confidence)
        actions = torch.zeros(state.shape[0], len(COMMANDS))
        for i, episode in enumerate(self._episode):
            scan = ranges[i].cpu()
            episode["memory"].add(state[i, :3], self.bearings.cpu(), scan, classes[i], keep[i])
            actions[i, self._command(episode, state[i], scan)] = 1.0
        return actions.to(logits.device)

    def _command(self, episode: dict[str, Any], state: Tensor, scan: Tensor) -> int:
        """The next command for one robot: look around until the current subgoal is seen, then the action head."""
        memory, targets = episode["memory"], episode["targets"]
        goal = memory.nearest(targets[episode["phase"]], state[:3])
        if episode["phase"] == 0 and goal is not None and (goal[0] ** 2 + goal[1] ** 2) ** 0.5 <= self.config.reach_m:
            episode["phase"] = 1
            goal = memory.nearest(targets[1], state[:3])
        if goal is None:
            return self._explore(episode, scan)
        known = torch.tensor([0.0 if goal is None else 1.0])
        dx, dy = (0.0, 0.0) if goal is None else goal
        features = goal_features(torch.tensor([dx]), torch.tensor([dy]), known)
        final = torch.tensor([float(episode["phase"])])
        logits = self.head(features, final, self._scan_input(scan.unsqueeze(0)), state[5:6])
        return int(logits.argmax(-1))

    def _explore(self, episode: dict[str, Any], scan: Tensor) -> int:
        """The subgoal has not been seen: look around, then head for open floor (the scanner's farthest ranges) and
        look around again every `explore_steps` steps."""
        if episode["searched"] < self.config.search_turns:
            episode["searched"] += 1
            return TURN_LEFT
        episode["explored"] += 1
        if episode["explored"] % self.config.explore_steps == 0:
            episode["searched"] = 0
        half = len(scan) // 2
        ahead = float(scan[half - 2 : half + 2].min())
        if ahead > self.config.open_m:
            return FORWARD
        return TURN_LEFT if float(scan[:half].mean()) >= float(scan[half:].mean()) else TURN_RIGHT

    def _scan_input(self, ranges: Tensor) -> Tensor:
        return ranges / self.config.max_range_m

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
            "action": self._action_loss(batch, ranges.detach(), truth_range),
        }
        accuracy = (logits.argmax(-1) == truth_class).float().mean()
        return sum(losses.values()), {**{k: v.item() for k, v in losses.items()}, "scan_accuracy": accuracy.item()}

    def _action_loss(self, batch: dict[str, Any], predicted: Tensor, truth: Tensor) -> Tensor:
        """The head learns from the true goal (with noise, sometimes hidden) and the true or the predicted scan."""
        goal = _privileged(batch, "goal")
        b = goal.shape[0]
        noise = self.config.goal_noise_m * torch.randn(b, 2, device=goal.device)
        known = (torch.rand(b, device=goal.device) >= self.config.unseen_rate).float()
        features = goal_features(goal[:, 0] + noise[:, 0], goal[:, 1] + noise[:, 1], known)
        use_predicted = torch.rand(b, 1, device=goal.device) < self.config.predicted_scan_rate
        scan = self._scan_input(torch.where(use_predicted, predicted, truth))
        bumper = batch[STATE_KEY][:, 5].float()
        logits = self.head(features, _privileged(batch, "phase").view(-1), scan, bumper)
        return F.cross_entropy(logits, batch[ACTION_KEY].float().argmax(-1))
