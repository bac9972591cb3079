"""LeRobot policy plugin: Language-Table's released BC checkpoint in PyTorch, as policy type `language_table`.

LeRobot imports this distribution at start-up (name prefix `lerobot_policy_`), which registers the config and the
action-clipping processor step. Convert the released Flax checkpoint with `python -m lerobot_policy_language_table.convert`.
"""

from lerobot_policy_language_table.configuration_language_table import LanguageTableConfig
from lerobot_policy_language_table.modeling_language_table import LanguageTablePolicy
from lerobot_policy_language_table.processor_language_table import (
    ClipActionProcessorStep,
    make_language_table_pre_post_processors,
)

__version__ = "0.1.0"
__all__ = [
    "ClipActionProcessorStep",
    "LanguageTableConfig",
    "LanguageTablePolicy",
    "make_language_table_pre_post_processors",
]
