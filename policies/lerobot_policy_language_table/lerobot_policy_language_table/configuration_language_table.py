"""`LanguageTableConfig`: the released Language-Table BC policy (LAVA with a ResNet stem and CLIP), type `language_table`.

Defaults are the released checkpoint's (`language_table_resnet_sim_local` config); the converter sets every size a
checkpoint determines, so a lab's own LAVA trained at other widths, heads or depths loads as well.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.optim import AdamConfig

IMAGE_KEY = "observation.images.top"
ACTION_KEY = "action"


def _default_inputs() -> dict[str, PolicyFeature]:
    return {IMAGE_KEY: PolicyFeature(type=FeatureType.VISUAL, shape=(3, 180, 320))}


def _default_outputs() -> dict[str, PolicyFeature]:
    return {ACTION_KEY: PolicyFeature(type=FeatureType.ACTION, shape=(2,))}


@PreTrainedConfig.register_subclass("language_table")
@dataclass
class LanguageTableConfig(PreTrainedConfig):
    """The released `SequenceLAVMSE` network and the benchmark's evaluation-time preprocessing.

    The policy keeps its own history of `sequence_length` frames (the first frame repeated at reset), crops the
    centre `crop_factor` of each camera frame and resizes it back, and reads the instruction from `task`.
    """

    input_features: dict[str, PolicyFeature] = field(default_factory=_default_inputs)
    output_features: dict[str, PolicyFeature] = field(default_factory=_default_outputs)
    # Images enter in [0, 1] unnormalised (the model normalises them itself); actions are mean/std normalised.
    normalization_mapping: dict[str, NormalizationMode] = field(
        default_factory=lambda: {
            "VISUAL": NormalizationMode.IDENTITY,
            "STATE": NormalizationMode.IDENTITY,
            "ACTION": NormalizationMode.MEAN_STD,
        }
    )

    sequence_length: int = 4
    crop_factor: float = 0.95
    resnet_input_size: int = 224
    # Channels of the ResNet stem (`64 * width_factor` upstream) and of the two pyramid convolutions after it.
    resnet_width: int = 64
    pyramid_channels: tuple[int, int] = (128, 256)
    d_model: int = 128
    # Attention heads of the language-to-pixel fusion layers (fixed at 2 upstream) and of the temporal transformer.
    fusion_heads: int = 2
    num_heads: int = 2
    fusion_layers: int = 4
    temporal_layers: int = 2
    dense_resnet_width: int = 1024
    dense_resnet_blocks: int = 2

    clip_vocab_size: int = 49408
    clip_context_length: int = 77
    clip_width: int = 512
    clip_heads: int = 8
    clip_layers: int = 12
    clip_embed_dim: int = 512

    max_action: float = 0.1

    optimizer_lr: float = 1e-3
    optimizer_eps: float = 1e-7

    @property
    def image_key(self) -> str:
        return next(iter(self.image_features))

    @property
    def observation_delta_indices(self) -> list[int]:
        # Training samples carry the frame history the network sees: the current frame and the 3 before it.
        return list(range(1 - self.sequence_length, 1))

    @property
    def action_delta_indices(self) -> None:
        return None

    @property
    def reward_delta_indices(self) -> None:
        return None

    def get_optimizer_preset(self) -> AdamConfig:
        return AdamConfig(lr=self.optimizer_lr, eps=self.optimizer_eps)

    def get_scheduler_preset(self) -> None:
        return None

    def validate_features(self) -> None:
        images = self.image_features
        if len(images) != 1:
            raise ValueError(f"language_table takes exactly one camera image input, got {sorted(images) or 'none'}")
        if images[self.image_key].shape[0] != 3:
            raise ValueError(f"language_table needs an RGB image (3, H, W), got {images[self.image_key].shape}")
        if len(self.pyramid_channels) != 2:
            raise ValueError(
                f"pyramid_channels holds the widths of the 2 pyramid convolutions, got {self.pyramid_channels}"
            )
        action = self.output_features.get(ACTION_KEY)
        if action is None or tuple(action.shape) != (2,):
            raise ValueError(f"language_table outputs a 2-D action {ACTION_KEY!r}, got {self.output_features}")
