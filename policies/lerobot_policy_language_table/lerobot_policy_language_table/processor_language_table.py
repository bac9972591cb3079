"""Pre/post-processors of the Language-Table policy: LeRobot's defaults, plus clipping the de-normalised action.

The action statistics of the released checkpoint travel as the (un)normaliser's `action` mean/std.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import torch
from lerobot.configs import PipelineFeatureType, PolicyFeature
from lerobot.processor import PolicyAction, PolicyProcessorPipeline
from lerobot.processor.factory import make_default_policy_processor_steps, make_policy_processor_pipelines
from lerobot.processor.pipeline import PolicyActionProcessorStep, ProcessorStepRegistry

from lerobot_policy_language_table.configuration_language_table import LanguageTableConfig


@ProcessorStepRegistry.register(name="language_table_clip_action")
@dataclass
class ClipActionProcessorStep(PolicyActionProcessorStep):
    """Clip each action component to [-max_abs, max_abs] (the benchmark's action space, 0.1 m per step)."""

    max_abs: float = 0.1

    def action(self, action: PolicyAction) -> PolicyAction:
        return action.clamp(-self.max_abs, self.max_abs)

    def get_config(self) -> dict[str, Any]:
        return {"max_abs": self.max_abs}

    def transform_features(
        self, features: dict[PipelineFeatureType, dict[str, PolicyFeature]]
    ) -> dict[PipelineFeatureType, dict[str, PolicyFeature]]:
        return features


def make_language_table_pre_post_processors(
    config: LanguageTableConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    """Rename -> batch -> device -> normalise; and un-normalise -> clip to ±max_action -> CPU."""
    steps = make_default_policy_processor_steps(config, dataset_stats)
    return make_policy_processor_pipelines(
        input_steps=[steps.rename_observations, steps.add_batch_dim, steps.to_device, steps.normalize],
        output_steps=[steps.unnormalize, ClipActionProcessorStep(max_abs=config.max_action), steps.to_cpu],
    )
