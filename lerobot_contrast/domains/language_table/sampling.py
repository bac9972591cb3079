"""i.i.d. instances: a benchmark-like reset, a goal drawn like the benchmark's reward reset, and its wording."""

from __future__ import annotations

from typing import Any

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.geometry import sample_scene
from lerobot_contrast.domains.language_table.wording import pick, render, sample_words

# The benchmark's per-reset goal tries before it declares FAILURE and resamples the board.
B2B_GOAL_TRIES = 10
TARGET_GOAL_TRIES = 100
# Resets per instance before we give up; a valid goal normally needs a handful.
MAX_RESETS = 1000


def _pair(names: list[str], rng: np.random.Generator) -> tuple[str, str]:
    i, j = rng.choice(len(names), size=2, replace=False)
    return names[int(i)], names[int(j)]


def clump(scene: Scene) -> tuple[str, list[str]]:
    """The benchmark's separate choice: the block with the smallest mean distance to its neighbours."""
    best: tuple[float, str, list[str]] = (np.inf, "", [])
    for name in scene.objects:
        near = fam.neighbours(scene, name)
        if near:
            here = scene.objects[name]
            mean = float(np.mean([here.distance_to(scene.objects[n]) for n in near]))
            if mean < best[0]:
                best = (mean, name, near)
    return best[1], best[2]


def sample_goal(family: str, scene: Scene, rng: np.random.Generator) -> dict[str, Any] | None:
    """A goal (without wording) for `scene`, or None where the benchmark's reset reports FAILURE.

    Target bounds are checked by `families.ground` afterwards, so the retry loops here only retry what
    the benchmark retries within one board.
    """
    names = list(scene.objects)
    if family == fam.BLOCK2BLOCK:
        for _ in range(B2B_GOAL_TRIES):
            block, target = _pair(names, rng)
            if scene.objects[block].distance_to(scene.objects[target]) >= board.BLOCK2BLOCK_MIN_START_DISTANCE:
                return {"block": block, "target_block": target}
        return None
    if family == fam.ABSOLUTE:
        return {"block": pick(rng, names), "location": pick(rng, sorted(board.LOCATIONS))}
    if family in (fam.RELATIVE, fam.B2B_RELATIVE):
        for _ in range(TARGET_GOAL_TRIES):
            if family == fam.RELATIVE:
                goal = {"block": pick(rng, names), "direction": pick(rng, sorted(board.DIRECTIONS))}
                goal["magnitude"] = pick(rng, sorted(board.RELATIVE_MAGNITUDES))
            else:
                block, target = _pair(names, rng)
                goal = {"block": block, "target_block": target, "direction": pick(rng, board.DIRECTIONS)}
            if fam.ground(family, goal, scene) is not None:
                return goal
        return None
    if family == fam.SEPARATE:
        block, avoid = clump(scene)
        if not avoid:
            return None
        if len(avoid) <= 2:
            mode = "named"
        elif len(avoid) == 3:
            mode = pick(rng, ("named", "group"))
        else:
            mode = "group"
        return {"block": block, "avoid": avoid, "avoid_mode": mode}
    raise ValueError(f"unknown Language-Table family {family!r}; choose from: {', '.join(fam.FAMILIES)}")


def sample_instance(family: str, blocks, rng: np.random.Generator, instance_id: str) -> Instance:
    """One i.i.d. instance of `family`: resample the board until the goal is groundable and not yet achieved.

    Unlike the benchmark, which accepts `separate` boards that are solved at reset, we reject every
    already-achieved goal so each instance is a real test.
    """
    for _ in range(MAX_RESETS):
        scene = sample_scene(blocks, rng)
        goal = sample_goal(family, scene, rng)
        grounded = None if goal is None else fam.ground(family, goal, scene)
        if grounded is None:
            continue
        instance = Instance(id=instance_id, family=family, instruction="", scene=scene, goal=grounded)
        if fam.is_achieved(instance, scene):
            continue
        words = sample_words(family, grounded, tuple(scene.objects), rng)
        return instance.derive(instruction=render(family, words), goal={**grounded, "words": words})
    raise RuntimeError(f"could not sample a valid {family} instance in {MAX_RESETS} resets")
