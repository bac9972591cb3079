"""`TabletopPointerConfig` (type `tabletop_pointer`): sizes, the objects it can point at, its vocabulary and camera calibration."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.optim import AdamConfig

IMAGE_KEY = "observation.images.top"
STATE_KEY = "observation.state"
ACTION_KEY = "action"
# Training-only targets from the simulator; never policy inputs (a real robot has none of them).
PRIVILEGED_PREFIX = "observation.privileged."

# Language-Table's 16 blocks (4 colours x 4 shapes): one detection heatmap each.
OBJECTS = tuple(f"{c}_{s}" for c in ("red", "blue", "green", "yellow") for s in ("moon", "cube", "star", "pentagon"))
# Image (u, v) in [0, 1] (u across, v down) -> board (x, y) metres on the plane of the blocks' top faces, for the
# benchmark camera (eye (0.75, 0, 0.5), pitch pi/5, fx = 0.803 * width). A lab's own camera puts its own here.
BENCHMARK_IMAGE_TO_BOARD = (
    (0.0, 0.945994, 0.082863),
    (0.953696, 0.0, -0.476848),
    (0.0, 0.682658, 1.0),
)


def _default_inputs() -> dict[str, PolicyFeature]:
    return {
        IMAGE_KEY: PolicyFeature(type=FeatureType.VISUAL, shape=(3, 180, 320)),
        STATE_KEY: PolicyFeature(type=FeatureType.STATE, shape=(4,)),
    }


def _default_outputs() -> dict[str, PolicyFeature]:
    return {ACTION_KEY: PolicyFeature(type=FeatureType.ACTION, shape=(2,))}


@PreTrainedConfig.register_subclass("tabletop_pointer")
@dataclass
class TabletopPointerConfig(PreTrainedConfig):
    """A pointer policy: per-object heatmaps from pixels, a text encoder that says which object to push and where,
    and an MLP that turns effector, object, goal and nearby-block positions into a heading and a speed.

    `observation.state` is (effector x, y, effector target x, y) in the board frame, as the simulator and the
    benchmark give it. The goal is read once per episode, from the first frame (`reset()` clears it).
    """

    input_features: dict[str, PolicyFeature] = field(default_factory=_default_inputs)
    output_features: dict[str, PolicyFeature] = field(default_factory=_default_outputs)
    # Positions are used in metres and the image in [0, 1], so nothing is normalised from dataset statistics.
    normalization_mapping: dict[str, NormalizationMode] = field(
        default_factory=lambda: {
            "VISUAL": NormalizationMode.IDENTITY,
            "STATE": NormalizationMode.IDENTITY,
            "ACTION": NormalizationMode.IDENTITY,
        }
    )

    objects: list[str] = field(default_factory=lambda: list(OBJECTS))
    # Words of the training dataset's instructions (built from its tasks when empty); others map to <unk>.
    vocabulary: list[str] = field(default_factory=list)
    max_words: int = 16
    image_height: int = 72
    image_width: int = 128
    image_to_board: list[list[float]] = field(default_factory=lambda: [list(r) for r in BENCHMARK_IMAGE_TO_BOARD])
    channels: int = 32
    word_dim: int = 32
    text_dim: int = 64
    head_hidden: int = 128
    # The action is a heading among this many directions and a speed; the head also sees this many nearest blocks.
    heading_bins: int = 16
    obstacles: int = 2
    # Blocks closer than this to the pushed block are its "group" when the instruction names none.
    neighbour_radius: float = 0.08
    max_action: float = 0.1
    # Probability that the action head trains on the predicted (not the true) pushed-block position.
    predicted_input_rate: float = 0.5
    # Std (metres) of noise on the true positions the action head trains on.
    position_noise: float = 0.01

    optimizer_lr: float = 1e-3
    optimizer_weight_decay: float = 1e-5

    def __post_init__(self) -> None:
        super().__post_init__()
        if len(self.image_to_board) != 3 or any(len(row) != 3 for row in self.image_to_board):
            raise ValueError(f"image_to_board must be a 3x3 matrix, got {self.image_to_board!r}")

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
            raise ValueError(
                f"tabletop_pointer needs {IMAGE_KEY} and {STATE_KEY}; it has {sorted(self.input_features)}"
            )
