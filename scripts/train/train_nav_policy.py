"""Train `vln_navigator` weights from a seed: teacher demonstrations, LeRobot training, DAgger, evaluation on 250
held-out arrangements (weights/TRAINING.md says which run the shipped weights came from).

    nice -n 10 .venv/bin/python scripts/train/train_nav_policy.py --recipe.output_dir=outputs/nav_policy --recipe.seed=0 --ship=true

Started again with the same settings it resumes where it stopped. The last line is the figures, as name=value pairs.
"""

import sys
from dataclasses import dataclass, field
from pathlib import Path

from lerobot_policy_vln_navigator import WEIGHTS

from lerobot_contrast.training.command import train_command
from lerobot_contrast.training.nav_recipe import NavRecipe, run


@dataclass
class TrainNavPolicy:
    recipe: NavRecipe = field(default_factory=NavRecipe)
    # Copy the final weights into the plugin (policies/lerobot_policy_vln_navigator/.../weights).
    ship: bool = False
    weights_dir: Path = WEIGHTS


if __name__ == "__main__":
    sys.exit(train_command(TrainNavPolicy, run))
