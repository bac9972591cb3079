"""LeRobot env plugin `language_table`: the tabletop simulator of lerobot-contrast inside LeRobot's own tools.

LeRobot imports this package (its name starts with `lerobot_env_`), which registers `--env.type=language_table`
for `lerobot-eval` and `lerobot-train`.
"""

from lerobot_env_language_table.config_language_table import LanguageTableEnvConfig

__all__ = ["LanguageTableEnvConfig"]
