"""Pre/post-processors of `vln_navigator`: LeRobot's default steps (rename, batch, device, identity normalisation).

The policy resizes images and tokenises the instruction itself, so a robot's full-size camera frames and raw `task`
strings go in unchanged, and the action comes out as the four one-hot discrete commands.
"""

from __future__ import annotations

from typing import Any

import torch
from lerobot.processor import PolicyAction, PolicyProcessorPipeline
from lerobot.processor.factory import make_default_policy_processor_steps, make_policy_processor_pipelines

from lerobot_policy_vln_navigator.configuration_vln_navigator import VLNNavigatorConfig


def make_vln_navigator_pre_post_processors(
    config: VLNNavigatorConfig,
    dataset_stats: dict[str, dict[str, torch.Tensor]] | None = None,
) -> tuple[
    PolicyProcessorPipeline[dict[str, Any], dict[str, Any]],
    PolicyProcessorPipeline[PolicyAction, PolicyAction],
]:
    steps = make_default_policy_processor_steps(config, dataset_stats)
    return make_policy_processor_pipelines(
        input_steps=[steps.rename_observations, steps.add_batch_dim, steps.to_device, steps.normalize],
        output_steps=[steps.unnormalize, steps.to_cpu],
    )
