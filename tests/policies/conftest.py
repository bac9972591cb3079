"""Session fixtures: one small synthetic checkpoint in the released format, and its conversion."""

from __future__ import annotations

from pathlib import Path

import pytest
from lerobot_policy_language_table.convert import convert

from .synthetic_checkpoint import SMALL_CLIP, random_variables, train_state, write_checkpoint


@pytest.fixture(scope="session")
def small_variables() -> dict:
    return random_variables(SMALL_CLIP, seed=0)


@pytest.fixture(scope="session")
def small_checkpoint(small_variables, tmp_path_factory) -> Path:
    return write_checkpoint(
        tmp_path_factory.mktemp("flax") / "bc_resnet_sim_checkpoint_955000", train_state(small_variables)
    )


@pytest.fixture(scope="session")
def converted(small_checkpoint, tmp_path_factory) -> Path:
    return convert(small_checkpoint, tmp_path_factory.mktemp("lerobot") / "language_table_bc")
