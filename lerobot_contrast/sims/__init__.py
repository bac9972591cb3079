"""Simulators as gymnasium envs, registered by string id when this package is imported."""

import gymnasium

from lerobot_contrast.tasks.language_table.board import MAX_EPISODE_STEPS

LANGUAGE_TABLE_ID = "lerobot_contrast/LanguageTable-v0"

if LANGUAGE_TABLE_ID not in gymnasium.registry:
    gymnasium.register(
        id=LANGUAGE_TABLE_ID,
        entry_point="lerobot_contrast.sims.language_table.env:LanguageTableEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
    )
