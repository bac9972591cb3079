"""The training scripts' command line: parse a config holding `recipe`, `ship` and `weights_dir`, run the recipe,
optionally ship its weights, and print the figures last as name=value pairs."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import draccus

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.extras import require_extra
from lerobot_contrast.training.recipe import RecipeError, ship


def train_command(config_class: type, run: Callable[[Any], dict[str, Any]]) -> int:
    """Exit status: 0 done, 2 a bad flag or a missing extra, 1 a recipe that could not finish (each one line)."""
    try:
        require_extra("train", f"python {sys.argv[0]}")
        config = draccus.parse(config_class)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except draccus.utils.ParsingError as error:
        cause = error.__cause__ if isinstance(error.__cause__, ValueError) else error
        print(f"error: {cause}", file=sys.stderr)
        return 2
    try:
        figures = run(config.recipe)
        if config.ship:
            ship(config.recipe, config.weights_dir)
    except RecipeError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in figures.items()))
    return 0
