"""The task protocol: what a task domain provides to plan and score a contrast-set evaluation."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Scene


class Task(Protocol):
    """A task domain: samples i.i.d. instances, grounds them in scenes, and judges outcomes."""

    name: str
    perturbations: PerturbationRegistry

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` i.i.d. evaluation instances, each with a valid, not yet achieved goal."""
        ...

    def storage_scene(self) -> Scene:
        """Where the objects are before the session's first trial, so that trial pays for a full set-up."""
        ...

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        """The same instruction set in `scene`, with scene-derived goal fields recomputed.

        None when the instruction cannot be grounded there (an object missing, a target off
        the workspace). Achievement is checked separately with `is_achieved`.
        """
        ...

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        """Whether `scene` satisfies the instance's goal, given that it started in `instance.scene`."""
        ...
