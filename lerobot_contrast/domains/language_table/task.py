"""LanguageTableTask: the Language-Table benchmark's five evaluation families as a contrast-set Task."""

from __future__ import annotations

from itertools import permutations

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.perturbations import PERTURBATIONS
from lerobot_contrast.domains.language_table.sampling import sample_instance


def instruction_to_array(text: str) -> np.ndarray:
    """The benchmark's obs["instruction"]: UTF-8 bytes of `text`, zero padded to (512,) int32."""
    data = text.encode("utf-8")
    if len(data) > board.INSTRUCTION_LENGTH:
        raise ValueError(
            f"instruction is {len(data)} UTF-8 bytes, more than the {board.INSTRUCTION_LENGTH} the "
            f"Language-Table observation holds; shorten it: {text[:60]!r}..."
        )
    out = np.zeros(board.INSTRUCTION_LENGTH, dtype=np.int32)
    out[: len(data)] = np.frombuffer(data, dtype=np.uint8)
    return out


def enumerate_conditions(block_mode: str = "BLOCK_8") -> list[tuple[str, ...]]:
    """The benchmark's task conditions: (family, block, ...) tuples; 696 for BLOCK_8.

    block2block (source, target), block2absolutelocation (block, location), block2relativelocation
    (block, direction; near/far not counted), block2blockrelativelocation (source, target, direction),
    separate (block, other block).
    """
    blocks = board.blocks_for_mode(block_mode)
    pairs = list(permutations(blocks, 2))
    return [
        *((fam.BLOCK2BLOCK, a, b) for a, b in pairs),
        *((fam.ABSOLUTE, a, loc) for a in blocks for loc in board.LOCATIONS),
        *((fam.RELATIVE, a, d) for a in blocks for d in board.DIRECTIONS),
        *((fam.B2B_RELATIVE, a, b, d) for a, b in pairs for d in board.DIRECTIONS),
        *((fam.SEPARATE, a, b) for a, b in pairs),
    ]


class LanguageTableTask(Task):
    """Language-Table pushing tasks: i.i.d. sampling, grounding, success and the six perturbations."""

    name = "language_table"

    def __init__(self, block_mode: str = "BLOCK_8", families=None, id_prefix: str = "lt-") -> None:
        self.block_mode = block_mode
        self.blocks = board.blocks_for_mode(block_mode)
        self.families = tuple(fam.FAMILIES if families is None else families)
        unknown = [f for f in self.families if f not in fam.FAMILIES]
        if unknown or not self.families:
            raise UserError(
                f"--families: unknown Language-Table families {unknown or '(none given)'}; "
                f"choose from: {', '.join(fam.FAMILIES)}"
            )
        self.id_prefix = id_prefix
        # A registry per task, so a user adding a perturbation to one task does not change the others.
        self.perturbations = PerturbationRegistry(self.name)
        for perturbation in PERTURBATIONS:
            self.perturbations.add(perturbation)

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` i.i.d. instances, family uniform over `self.families`, ids f"{id_prefix}{k:04d}"."""
        out = []
        for k in range(n):
            family = self.families[int(rng.integers(len(self.families)))]
            out.append(sample_instance(family, self.blocks, rng, f"{self.id_prefix}{k:04d}"))
        return out

    def storage_scene(self) -> Scene:
        """The scene before the first trial: the blocks in a row beside the board's right edge.

        Off the workspace, so staging the first instance pays for carrying every block onto the board.
        """
        xs = np.linspace(board.X_MIN, board.X_MAX, len(self.blocks))
        y = board.Y_MAX + board.WORKSPACE_BOUNDS_BUFFER
        return Scene(objects={name: Pose(float(x), y, 0.0) for name, x in zip(self.blocks, xs, strict=True)})

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        return fam.rebase(instance, scene)

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        return fam.is_achieved(instance, scene)

    def reference_length(self, instance: Instance) -> float:
        """The noise-free push oracle's effector path length in metres, the reference for SPL."""
        from lerobot_contrast.domains.language_table.oracle import reference_path  # the simulator needs pymunk

        return reference_path(self, instance).length_m

    def push_target(self, instance: Instance, scene: Scene) -> tuple[str, np.ndarray]:
        return fam.push_target(instance, scene)

    def goal_position(self, instance: Instance) -> tuple[float, float] | None:
        """Where the pushed block should end up."""
        try:
            _, xy = self.push_target(instance, instance.scene)
        except (KeyError, ValueError):
            return None
        return float(xy[0]), float(xy[1])

    def enumerate_conditions(self) -> list[tuple[str, ...]]:
        return enumerate_conditions(self.block_mode)
