"""`VLNNavigatorConfig` (type `vln_navigator`): input size, the furniture it knows, its vocabulary and camera model."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.optim import AdamConfig

IMAGE_KEY = "observation.images.front"
# The aligned depth image (metres along the optical axis): the navigation protocol's `front_depth`.
DEPTH_KEY = "observation.images.front_depth"
MISSING_DEPTH = (
    "vln_navigator needs the robot's aligned depth image (observation.images.front_depth): "
    "give --robot.use_depth=true on --robot.type=locobot (vln_sim gives it unless --robot.depth=false)"
)
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
        DEPTH_KEY: PolicyFeature(type=FeatureType.VISUAL, shape=(1, 480, 640)),
        STATE_KEY: PolicyFeature(type=FeatureType.STATE, shape=(len(STATE_NAMES),)),
    }


def _default_outputs() -> dict[str, PolicyFeature]:
    return {ACTION_KEY: PolicyFeature(type=FeatureType.ACTION, shape=(len(COMMANDS),))}


@PreTrainedConfig.register_subclass("vln_navigator")
@dataclass
class VLNNavigatorConfig(PreTrainedConfig):
    """A navigator in two learned parts, a map and a planner: a column scanner reads, per image column, what
    furniture (or wall) the camera sees; a text reader names the two subgoal objects; the aligned depth image gives,
    per column, how far the nearest obstacle is (pixels neither floor nor ceiling, by the camera model below). An
    occupancy grid of those ranges (and bumps) and where each category was seen is planned on, geodesically, towards
    the current subgoal (exploring the grid's frontier while it is unseen) to give one of the four discrete commands.

    `observation.state` is the navigation protocol's (odom.x, odom.y, odom.theta, x.vel, theta.vel, bumper).
    Odometry only places what was seen in the episode's own frame (`reset()` clears the map and the memory).
    """

    input_features: dict[str, PolicyFeature] = field(default_factory=_default_inputs)
    output_features: dict[str, PolicyFeature] = field(default_factory=_default_outputs)
    # The image is used in [0, 1], depth and the state in metres and radians, so nothing uses dataset statistics.
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
    # The depth camera's height above the floor; a depth pixel is an obstacle when the point it sees stands between
    # these heights (lower is floor, higher is ceiling).
    camera_height_m: float = 0.55
    obstacle_min_m: float = 0.08
    obstacle_max_m: float = 1.9
    channels: int = 24
    word_dim: int = 32
    text_dim: int = 48
    # A subgoal counts as passed when the robot comes this close to where its surface was seen (metres) from at most
    # `confirm_m` away (farther sightings still guide the way there).
    reach_m: float = 0.55
    confirm_m: float = 2.5
    # Turns in place while the current subgoal has not been seen (12 x 30 degrees: a full look around), before
    # exploring the map's frontier.
    search_turns: int = 12
    # Per category, the memory keeps this many seen surface points; the scanner's class must be this sure.
    memory_points: int = 300
    seen_confidence: float = 0.6
    # The map's cell size, the robot's radius (cells nearer an obstacle are all but blocked) and the extra clearance
    # routes keep where they can; the planner scores each heading at a point this far ahead.
    map_resolution_m: float = 0.1
    robot_radius_m: float = 0.2
    clearance_m: float = 0.25
    lookahead_m: float = 0.3
    # Sightings nearer than this do not place furniture in the memory (up close one object fills the view and the
    # scanner's class is least sure).
    near_m: float = 1.0

    optimizer_lr: float = 1e-3
    optimizer_weight_decay: float = 1e-5

    def set_dataset_feature_metadata(self, features: dict[str, Any]) -> None:
        """Called by LeRobot's `make_policy`: privileged training targets are never inputs; depth is one even when
        the training dataset has none (training supervises only the image's scanner and the instruction's reader)."""
        inputs = {k: v for k, v in self.input_features.items() if not k.startswith(PRIVILEGED_PREFIX)}
        self.input_features = {**inputs, **{DEPTH_KEY: _default_inputs()[DEPTH_KEY]}}

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

    def missing_input_hint(self, missing: list[str]) -> str | None:
        """The one line to show when a robot lacks inputs this policy reads (None: the generic message)."""
        return MISSING_DEPTH if missing == [DEPTH_KEY] else None

    def validate_features(self) -> None:
        if IMAGE_KEY not in self.input_features or STATE_KEY not in self.input_features:
            raise ValueError(f"vln_navigator needs {IMAGE_KEY} and {STATE_KEY}; it has {sorted(self.input_features)}")
