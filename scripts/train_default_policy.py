"""Reproduce the shipped `tabletop_pointer` weights from a seed: demonstrations, LeRobot training, DAgger, evaluation.

    .venv/bin/python scripts/train_default_policy.py --output_dir=outputs/default_policy --seed=0 --ship=true

Started again with the same settings it resumes where it stopped. The last line is the figures, as name=value pairs.
"""

import sys
from dataclasses import dataclass, field
from pathlib import Path

import draccus
from lerobot_policy_tabletop_pointer import WEIGHTS

from lerobot_contrast.training.recipe import Recipe, RecipeError, run, ship


@dataclass
class TrainDefaultPolicy:
    recipe: Recipe = field(default_factory=Recipe)
    # Copy the final weights into the plugin (policies/lerobot_policy_tabletop_pointer/.../weights).
    ship: bool = False
    weights_dir: Path = WEIGHTS


def main(config: TrainDefaultPolicy) -> None:
    figures = run(config.recipe)
    if config.ship:
        ship(config.recipe, config.weights_dir)
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in figures.items()))


if __name__ == "__main__":
    try:
        parsed = draccus.parse(TrainDefaultPolicy)
    except draccus.utils.ParsingError as error:
        cause = error.__cause__ if isinstance(error.__cause__, ValueError) else error
        print(f"error: {cause}", file=sys.stderr)
        sys.exit(2)
    try:
        main(parsed)
    except RecipeError as error:
        print(f"error: {error}", file=sys.stderr)
        sys.exit(1)
