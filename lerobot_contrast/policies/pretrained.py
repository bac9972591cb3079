"""Any LeRobot `PreTrainedPolicy`, with its pre/post processors, as a policy the runner drives.

The trial's instruction reaches the policy as `task`; `reset()` runs between trials. Features come from
the robot (LeRobot's own `hw_to_dataset_features`), so a policy whose inputs the robot does not provide
is refused up front, with the keys to map through `--rename_map`.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Mapping, Sequence
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np
import torch
from lerobot.common.control_utils import predict_action
from lerobot.configs import PreTrainedConfig
from lerobot.configs.types import FeatureType
from lerobot.policies import get_policy_class, make_policy_config, make_pre_post_processors
from lerobot.policies.utils import make_robot_action
from lerobot.utils.feature_utils import build_dataset_frame, dataset_to_policy_features, hw_to_dataset_features

from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.policies.base import PolicyArgs, PolicyError
from lerobot_contrast.record.third_party import quiet_hub_client

if TYPE_CHECKING:
    from lerobot.robots import Robot


class PolicyLoadError(PolicyError):
    pass


def build(args: PolicyArgs, robot: Robot, task: Task, rename_map: Mapping[str, str]) -> PretrainedPolicy:
    """--policy.path, or a LeRobot --policy.type built fresh with random weights."""
    return PretrainedPolicy(robot, args.path, args.type, args.device, rename_map, args.use_amp)


def robot_dataset_features(robot: Robot) -> dict[str, dict]:
    """The robot's features in LeRobot dataset form (`observation.state`, `observation.images.*`, `action`)."""
    return {
        **hw_to_dataset_features(robot.action_features, "action"),
        **hw_to_dataset_features(robot.observation_features, "observation"),
    }


def looks_like_path(value: str) -> bool:
    """Absolute, `.`/`~`-led, or with more separators than a Hub repo id (`user/name`) has."""
    slashes = value.count("/") + (value.count(os.sep) if os.sep != "/" else 0)
    return Path(value).is_absolute() or value.startswith((".", "~")) or slashes > 1


def _load_config(path: str, device: str | None) -> PreTrainedConfig:
    if looks_like_path(path) and not Path(path).expanduser().exists():
        raise PolicyLoadError(f"--policy.path: no such directory: {path}")
    try:
        # An unreachable Hub or a directory without a config: this function's one line, not the libraries' lines.
        with quiet_hub_client("lerobot.configs"):
            config = PreTrainedConfig.from_pretrained(path)
    except Exception as error:
        detail = " ".join(str(error).split())[:200]
        raise PolicyLoadError(
            f"--policy.path: cannot load a LeRobot policy config from {path!r} ({detail}); "
            "give a directory written by save_pretrained or a Hub repo id"
        ) from None
    config.pretrained_path = Path(path) if Path(path).exists() else path
    if device is not None:
        config.device = device
    return config


def save_fresh_policy(robot: Robot, policy_type: str, directory: Path, **overrides: Any) -> Path:
    """A random-weight LeRobot policy shaped for `robot`, saved as `--policy.path` loads it (smoke tests, benchmarks)."""
    features = robot_dataset_features(robot)
    config = _fresh_config(policy_type, overrides.pop("device", None), features, **overrides)
    policy = get_policy_class(config.type)(config)
    preprocessor, postprocessor = make_pre_post_processors(config, dataset_stats=None)
    for part in (policy, preprocessor, postprocessor):
        part.save_pretrained(directory)
    return directory


def _fresh_config(
    policy_type: str, device: str | None, features: dict[str, dict], **overrides: Any
) -> PreTrainedConfig:
    if device is not None:
        overrides["device"] = device
    try:
        config = make_policy_config(policy_type, **overrides)
    except ValueError as error:
        raise PolicyLoadError(f"--policy.type: {' '.join(str(error).split())[:300]}") from None
    if hasattr(config, "pretrained_backbone_weights"):  # a fresh policy is all random: fetch no vision backbone
        config.pretrained_backbone_weights = None
    policy_features = dataset_to_policy_features(features)
    config.output_features = {k: v for k, v in policy_features.items() if k == "action"}
    config.input_features = {k: v for k, v in policy_features.items() if k != "action"}
    return config


def _check_rename_map(config: PreTrainedConfig, features: dict[str, dict], rename_map: Mapping[str, str]) -> None:
    """Every key renamed is one the robot gives, and every new name is one the policy reads."""
    robot_keys = sorted(key for key in features if key != "action")
    for key, name in rename_map.items():
        if key not in robot_keys:
            raise PolicyLoadError(
                f"--rename_map: the robot gives no {key!r}; map one of its keys ({', '.join(robot_keys)})"
            )
        if name not in config.input_features:
            raise PolicyLoadError(
                f"--rename_map: {key!r} is mapped to {name!r}, which the policy does not read "
                f"(it reads {', '.join(sorted(config.input_features)) or 'nothing'})"
            )


def _check_inputs(
    config: PreTrainedConfig, features: dict[str, dict], rename_map: Mapping[str, str]
) -> dict[str, tuple[int, int]]:
    """Refuse inputs the robot cannot give; return the camera frames the evaluator resizes for the policy (the
    robot's key: the policy's height and width)."""
    _check_rename_map(config, features, rename_map)
    provided = {rename_map.get(key, key) for key in features if key != "action"}
    missing = sorted(set(config.input_features) - provided)
    hint = getattr(config, "missing_input_hint", lambda keys: None)(missing)  # a policy naming the robot's option
    if missing and hint:
        raise PolicyLoadError(hint)
    if missing:
        raise PolicyLoadError(
            f"the policy expects {', '.join(missing)}, which the robot does not provide "
            f"(it gives {', '.join(sorted(provided))}); map robot keys to them with "
            '--rename_map=\'{"observation.images.ROBOT_CAMERA": "POLICY_KEY"}\''
        )
    given = {rename_map.get(key, key): feature for key, feature in dataset_to_policy_features(features).items()}
    robot_key = {rename_map.get(key, key): key for key in features}
    resized = {}
    for key, wanted in config.input_features.items():
        expected, actual = tuple(wanted.shape), tuple(given[key].shape)
        if expected == actual or (wanted.type is FeatureType.VISUAL and _resizes(config, expected, actual)):
            continue
        if wanted.type is FeatureType.VISUAL and _same_view(expected, actual):
            resized[robot_key[key]] = (expected[1], expected[2])
            continue
        raise PolicyLoadError(
            f"the policy's {key} has shape {expected} but the robot gives {actual}; "
            "use a policy trained on this robot's features, or set the camera to the policy's size or aspect ratio"
        )
    return resized


def _same_view(expected: tuple[int, ...], actual: tuple[int, ...]) -> bool:
    """Same channels and the same aspect ratio (within 1 %): the camera's frame, scaled, is the policy's view."""
    if not (len(expected) == len(actual) == 3 and expected[0] == actual[0]):
        return False
    return abs(expected[1] * actual[2] - actual[1] * expected[2]) <= 0.01 * expected[1] * actual[2]


# Config fields by which a policy declares the image size it resizes any frame to before its network sees it.
RESIZE_FIELDS = ("resize_shape", "image_resize_shape", "resize_imgs_with_padding", "image_height")


def _resizes(config: PreTrainedConfig, expected: tuple[int, ...], actual: tuple[int, ...]) -> bool:
    """Same channels, another size, and a policy that resizes frames itself: adapted, not refused."""
    same_channels = len(expected) == len(actual) == 3 and expected[0] == actual[0]
    return same_channels and any(getattr(config, name, None) is not None for name in RESIZE_FIELDS)


def _build_policy(config: PreTrainedConfig, path: str | None) -> Any:
    policy_class = get_policy_class(config.type)
    try:
        return policy_class.from_pretrained(path, config=config) if path is not None else policy_class(config)
    except ValueError as error:  # LeRobot's policies check their config's features as they are built
        flag = f"--policy.path={path}" if path is not None else f"--policy.type={config.type}"
        raise PolicyLoadError(
            f"{flag}: cannot build the policy ({' '.join(str(error).split())[:200]}); its config.json must "
            "declare the input and output features it was trained with"
        ) from None


class PretrainedPolicy:
    """A LeRobot policy loaded from `--policy.path` (or built fresh from `--policy.type`) for one robot."""

    def __init__(
        self,
        robot: Robot,
        path: str | None = None,
        policy_type: str | None = None,
        device: str | None = None,
        rename_map: Mapping[str, str] | None = None,
        use_amp: bool = False,
    ) -> None:
        self.features = robot_dataset_features(robot)
        self.robot_type = robot.robot_type
        rename_map = dict(rename_map or {})
        if path is not None:
            config = _load_config(path, device)
        else:
            config = _fresh_config(str(policy_type), device, self.features)
        self.resized = _check_inputs(config, self.features, rename_map)
        for key, (height, width) in self.resized.items():
            shape = self.features[key]["shape"]
            print(f"policy: {key} frames of {shape[1]}x{shape[0]} are resized to {width}x{height}, the policy's size")
        self.policy = _build_policy(config, path)
        self.policy.to(config.device).eval()
        overrides = {"device_processor": {"device": str(config.device)}}
        if rename_map:
            overrides["rename_observations_processor"] = {"rename_map": rename_map}
        self.preprocessor, self.postprocessor = make_pre_post_processors(
            config,
            pretrained_path=path,
            **({"preprocessor_overrides": overrides} if path is not None else {}),
        )
        self.name = config.type
        self.device = torch.device(config.device)
        self.use_amp = use_amp
        self.instruction = ""
        self.memory: dict[str, Any] = {}  # the episode's own state, for a policy that batches lanes

    @property
    def batches_lanes(self) -> bool:
        """Whether the policy keeps each episode's memory apart, so one call can step many episodes (lanes)."""
        return hasattr(self.policy, "lane_step")

    def reset(self, context: TrialContext) -> None:
        self.instruction = context.instance.instruction
        self.memory = {}
        self.policy.reset()
        self.preprocessor.reset()
        self.postprocessor.reset()

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]:
        if self.batches_lanes:  # the lanes' own path, so one lane and many give the same actions
            return self.act_lanes([observation], [self.instruction], [self.memory])[0]
        action = predict_action(
            self._frame(observation),
            self.policy,
            self.device,
            self.preprocessor,
            self.postprocessor,
            self.use_amp,
            task=self.instruction,
            robot_type=self.robot_type,
        )
        return make_robot_action(action, self.features)

    def _frame(self, observation: Mapping[str, Any]) -> dict[str, Any]:
        """The observation as LeRobot's dataset frame, its camera frames at the policy's size (area averaging, as a
        camera set to that size would bin its pixels)."""
        frame = build_dataset_frame(self.features, dict(observation), prefix="observation")
        for key, (height, width) in self.resized.items():
            frame[key] = cv2.resize(frame[key], (width, height), interpolation=cv2.INTER_AREA)
        return frame

    def lane_twin(self) -> PretrainedPolicy:
        """The same network behind processors of its own, to answer other lanes from another thread (a processor
        pipeline keeps the transition it is working on)."""
        twin = copy.copy(self)
        twin.preprocessor, twin.postprocessor = copy.deepcopy(self.preprocessor), copy.deepcopy(self.postprocessor)
        return twin

    def act_lanes(
        self, observations: Sequence[Mapping[str, Any]], instructions: Sequence[str], memories: list[dict[str, Any]]
    ) -> list[dict[str, float]]:
        """One control step of several episodes in one call of the policy's `lane_step`: frames are batched on the
        CPU and reach the policy's device in one transfer; `memories[i]` is episode i's own state."""
        frames = [self._frame(observation) for observation in observations]
        batch: dict[str, Any] = {key: _stacked([frame[key] for frame in frames], key) for key in frames[0]}
        batch["task"], batch["robot_type"] = list(instructions), self.robot_type
        amp = self.device.type == "cuda" and self.use_amp
        with torch.inference_mode(), torch.autocast(device_type=self.device.type) if amp else nullcontext():
            actions = self.postprocessor(self.policy.lane_step(self.preprocessor(batch), memories))
        return [make_robot_action(row.unsqueeze(0), self.features) for row in actions]


def _stacked(values: Sequence[Any], key: str) -> torch.Tensor:
    """The rows of one observation key as a batch, as LeRobot's `prepare_observation_for_inference` gives each row
    (images channels first, uint8 scaled to [0, 1] in float32), with the same values to the last bit: the pixels
    are reordered while they are still bytes and converted in one pass, a quarter of the memory traffic."""
    batch = torch.from_numpy(np.stack(values))
    if "image" not in key:
        return batch
    batch = batch.permute(0, 3, 1, 2)
    if batch.dtype != torch.uint8:
        return batch.contiguous()
    return batch.to(torch.float32, memory_format=torch.contiguous_format).div_(255)
