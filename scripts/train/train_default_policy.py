"""Reproduce the shipped `tabletop_pointer` weights from a seed: demonstrations, LeRobot training, DAgger, evaluation.

    .venv/bin/python scripts/train/train_default_policy.py --recipe.output_dir=outputs/default_policy --recipe.seed=0 --ship=true

Started again with the same settings it resumes where it stopped. The last line is the figures, as name=value pairs.
"""

import sys
from dataclasses import dataclass, field
from pathlib import Path

from lerobot_policy_tabletop_pointer import WEIGHTS

from lerobot_contrast.training.command import train_command
from lerobot_contrast.training.recipe import Recipe, run


@dataclass
class TrainDefaultPolicy:
    recipe: Recipe = field(default_factory=Recipe)
    # Copy the final weights into the plugin (policies/lerobot_policy_tabletop_pointer/.../weights).
    ship: bool = False
    weights_dir: Path = WEIGHTS


if __name__ == "__main__":
    sys.exit(train_command(TrainDefaultPolicy, run))
