"""`VLNNavigatorConfig` (type `vln_navigator`): input size, the furniture it knows, its vocabulary and camera model."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.optim import AdamConfig

IMAGE_KEY = "observation.images.front"
STATE_KEY = "observation.state"
ACTION_KEY = "action"
# Training-only targets from the simulator; never policy inputs (a real robot has none of them).
PRIVILEGED_PREFIX = "observation.privileged."
# The navigation protocol's state and discrete actions, in its order.
STATE_NAMES = ("odom.x", "odom.y", "odom.theta", "x.vel", "theta.vel", "bumper")
COMMANDS = ("forward", "turn_left", "turn_right", "stop")
# The furniture categories of the apartment (one class each; one more class is "wall or nothing").
CATEGORIES = ("bed", "bookshelf", "chair", "couch", "desk", "dresser", "lamp", "plant", "table", "tv_stand")


def _default_inputs() -> dict[str, PolicyFeature]:
    return {
        IMAGE_KEY: PolicyFeature(type=FeatureType.VISUAL, shape=(3, 480, 640)),
        STATE_KEY: PolicyFeature(type=FeatureType.STATE, shape=(len(STATE_NAMES),)),
    }


def _default_outputs() -> dict[str, PolicyFeature]:
    return {ACTION_KEY: PolicyFeature(type=FeatureType.ACTION, shape=(len(COMMANDS),))}


@PreTrainedConfig.register_subclass("vln_navigator")
@dataclass
class VLNNavigatorConfig(PreTrainedConfig):
    """A navigator in three learned parts and a memory: a column scanner reads, per image column, what furniture
    (or wall) the ray meets and how far; a text reader names the two subgoal objects; an action head turns the
    remembered subgoal's position, the range scan and the bumper into one of the four discrete commands.

    `observation.state` is the navigation protocol's (odom.x, odom.y, odom.theta, x.vel, theta.vel, bumper).
    Odometry only places what the scanner saw in the episode's own frame (`reset()` clears the memory).
    """

    input_features: dict[str, PolicyFeature] = field(default_factory=_default_inputs)
    output_features: dict[str, PolicyFeature] = field(default_factory=_default_outputs)
    # The image is used in [0, 1] and the state in metres and radians, so nothing uses dataset statistics.
    normalization_mapping: dict[str, NormalizationMode] = field(
        default_factory=lambda: {
            "VISUAL": NormalizationMode.IDENTITY,
            "STATE": NormalizationMode.IDENTITY,
            "ACTION": NormalizationMode.IDENTITY,
        }
    )

    categories: list[str] = field(default_factory=lambda: list(CATEGORIES))
    # Words of the training dataset's instructions (built from its tasks when empty); others map to <unk>.
    vocabulary: list[str] = field(default_factory=list)
    max_words: int = 24
    image_height: int = 48
    image_width: int = 64
    # Scan columns across the image, and the camera's horizontal field of view that maps them to bearings.
    columns: int = 32
    hfov_deg: float = 69.0
    max_range_m: float = 8.0
    channels: int = 24
    word_dim: int = 32
    text_dim: int = 48
    head_hidden: int = 128
    # A subgoal counts as passed when the robot comes this close to where its surface was seen (metres).
    reach_m: float = 0.55
    # Turns in place while the current subgoal has not been seen (12 x 30 degrees: a full look around).
    search_turns: int = 12
    # Then, while it stays unseen, drive towards open floor (forward while the way ahead is this clear), looking
    # around again every `explore_steps` steps.
    explore_steps: int = 8
    open_m: float = 1.0
    # Per category, the memory keeps this many seen surface points; the scanner's class must be this sure.
    memory_points: int = 300
    seen_confidence: float = 0.6
    # Training: the action head sees the predicted (not the true) scan at this rate, true goals with this noise,
    # and no goal (as before the subgoal is seen) at `unseen_rate`.
    predicted_scan_rate: float = 0.5
    goal_noise_m: float = 0.1
    unseen_rate: float = 0.1

    optimizer_lr: float = 1e-3
    optimizer_weight_decay: float = 1e-5

    def set_dataset_feature_metadata(self, features: dict[str, Any]) -> None:
        """Called by LeRobot's `make_policy`: privileged training targets are never inputs."""
        self.input_features = {k: v for k, v in self.input_features.items() if not k.startswith(PRIVILEGED_PREFIX)}

    @property
    def observation_delta_indices(self) -> None:
        return None

    @property
    def action_delta_indices(self) -> None:
        return None

    @property
    def reward_delta_indices(self) -> None:
        return None

    def get_optimizer_preset(self) -> AdamConfig:
        return AdamConfig(lr=self.optimizer_lr, weight_decay=self.optimizer_weight_decay)

    def get_scheduler_preset(self) -> None:
        return None

    def validate_features(self) -> None:
        if IMAGE_KEY not in self.input_features or STATE_KEY not in self.input_features:
            raise ValueError(f"vln_navigator needs {IMAGE_KEY} and {STATE_KEY}; it has {sorted(self.input_features)}")
