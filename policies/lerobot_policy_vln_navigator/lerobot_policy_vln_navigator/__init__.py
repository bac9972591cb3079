"""LeRobot policy plugin `vln_navigator`: a language-conditioned pixel navigator for two-subgoal VLN.

`WEIGHTS` is the directory of the shipped, trained policy (config, safetensors and processor files).
"""

from pathlib import Path

from lerobot_policy_vln_navigator.configuration_vln_navigator import VLNNavigatorConfig
from lerobot_policy_vln_navigator.modeling_vln_navigator import VLNNavigatorPolicy
from lerobot_policy_vln_navigator.processor_vln_navigator import make_vln_navigator_pre_post_processors

WEIGHTS = Path(__file__).parent / "weights"

__all__ = ["WEIGHTS", "VLNNavigatorConfig", "VLNNavigatorPolicy", "make_vln_navigator_pre_post_processors"]
