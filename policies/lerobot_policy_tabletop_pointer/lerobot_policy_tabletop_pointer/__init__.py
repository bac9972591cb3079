"""LeRobot policy plugin `tabletop_pointer`: a language-conditioned pixel policy for Language-Table pushing.

`WEIGHTS` is the directory of the shipped, trained policy (config, safetensors and processor files).
"""

from pathlib import Path

from lerobot_policy_tabletop_pointer.configuration_tabletop_pointer import TabletopPointerConfig
from lerobot_policy_tabletop_pointer.modeling_tabletop_pointer import TabletopPointerPolicy
from lerobot_policy_tabletop_pointer.processor_tabletop_pointer import make_tabletop_pointer_pre_post_processors

WEIGHTS = Path(__file__).parent / "weights"

__all__ = ["WEIGHTS", "TabletopPointerConfig", "TabletopPointerPolicy", "make_tabletop_pointer_pre_post_processors"]
