"""Reproduce the shipped `vln_navigator` weights from a seed: teacher demonstrations, LeRobot training, DAgger,
evaluation on 250 held-out arrangements.

    nice -n 10 .venv/bin/python scripts/train_nav_policy.py --recipe.output_dir=outputs/nav_policy --recipe.seed=0 --ship=true

Started again with the same settings it resumes where it stopped. The last line is the figures, as name=value pairs.
"""

import sys
from dataclasses import dataclass, field
from pathlib import Path

import draccus
from lerobot_policy_vln_navigator import WEIGHTS

from lerobot_contrast.training.nav_recipe import NavRecipe, run
from lerobot_contrast.training.recipe import RecipeError, ship


@dataclass
class TrainNavPolicy:
    recipe: NavRecipe = field(default_factory=NavRecipe)
    # Copy the final weights into the plugin (policies/lerobot_policy_vln_navigator/.../weights).
    ship: bool = False
    weights_dir: Path = WEIGHTS


def main(config: TrainNavPolicy) -> None:
    figures = run(config.recipe)
    if config.ship:
        ship(config.recipe, config.weights_dir)
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in figures.items()))


if __name__ == "__main__":
    try:
        parsed = draccus.parse(TrainNavPolicy)
    except draccus.utils.ParsingError as error:
        cause = error.__cause__ if isinstance(error.__cause__, ValueError) else error
        print(f"error: {cause}", file=sys.stderr)
        sys.exit(2)
    try:
        main(parsed)
    except RecipeError as error:
        print(f"error: {error}", file=sys.stderr)
        sys.exit(1)
