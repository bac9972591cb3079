"""The Language-Table perturbations (ΔL, ΔLB1, ΔLB2, ΔS, ΔSB1, ΔSB2), applied in the scene the robot left behind.
Each returns an instance grounded in its scene and not yet achieved there, or None where it does not apply.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Scene, distance_to_segment
from lerobot_contrast.domains.language_table import board, synonyms
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.geometry import sample_free_pose, xy
from lerobot_contrast.domains.language_table.wording import flip_words, render, sample_words

# A moved block travels at least this far, so the change is one a person (and the policy) notices,
# and for ΔSB the expected behaviour really differs.
MIN_MOVE = 0.1
# ΔS keeps the moved distractor this far from the pushed block's path and from every block the
# instruction involves, so the expected behaviour stays the same.
KEEP_CLEAR = 0.1
MOVE_TRIES = 200
PARAPHRASE_TRIES = 50

PERTURBATIONS = PerturbationRegistry("language_table")


def _finish(instance: Instance, goal: Mapping[str, Any], scene: Scene | None = None) -> Instance | None:
    """Re-render, ground in the (possibly new) scene, and drop results that are already achieved."""
    scene = instance.scene if scene is None else scene
    out = instance.derive(instruction=render(instance.family, goal["words"]), goal=dict(goal))
    out = fam.rebase(out, scene)
    return None if out is None or fam.is_achieved(out, scene) else out


@PERTURBATIONS.register("L", "L", "paraphrase: same goal, other verbs/prepositions/synonyms")
def paraphrase(instance: Instance, rng: np.random.Generator) -> Instance | None:
    blocks = tuple(instance.scene.objects)
    for _ in range(PARAPHRASE_TRIES):
        words = sample_words(instance.family, instance.goal, blocks, rng, free_order=True)
        if render(instance.family, words) != instance.instruction:
            return _finish(instance, {**instance.goal, "words": words})
    return None


@PERTURBATIONS.register("LB1", "LB", "swap the source and target referring expressions")
def swap_source_target(instance: Instance, rng: np.random.Generator) -> Instance | None:
    goal, words = instance.goal, instance.goal["words"]
    if instance.family in (fam.BLOCK2BLOCK, fam.B2B_RELATIVE):
        new = {**goal, "block": goal["target_block"], "target_block": goal["block"]}
        new["words"] = {**words, "block": words["target"], "target": words["block"]}
    elif instance.family == fam.SEPARATE and goal["avoid_mode"] == "named" and len(goal["avoid"]) == 1:
        new = {**goal, "block": goal["avoid"][0], "avoid": [goal["block"]]}
        new["words"] = {**words, "block": words["avoid"], "avoid": words["block"]}
    else:
        return None
    return _finish(instance, new)


@PERTURBATIONS.register("LB2", "LB", "flip direction/location words (left<->right, up<->down, diagonals)")
def flip_directions(instance: Instance, rng: np.random.Generator) -> Instance | None:
    words = flip_words(instance.family, instance.goal, rng)
    if words is None:
        return None
    new = {**instance.goal, "words": words}
    if instance.family == fam.ABSOLUTE:
        new["location"] = synonyms.LOCATION_FLIP[instance.goal["location"]]
    else:
        new["direction"] = synonyms.DIRECTION_FLIP[instance.goal["direction"]]
    return _finish(instance, new)


def _move(
    instance: Instance,
    name: str,
    rng: np.random.Generator,
    accept: Callable[[Instance], bool],
    center: np.ndarray | None = None,
    radius: float | None = None,
    tries: int = MOVE_TRIES,
) -> Instance | None:
    """Move block `name` to a sampled free place where the instance grounds, is not achieved, and `accept`s."""
    for _ in range(tries):
        pose = sample_free_pose(instance.scene, name, rng, center, radius)
        if pose is None:
            continue
        scene = instance.scene.with_object(name, pose)
        out = fam.rebase(instance, scene)
        if out is not None and not fam.is_achieved(out, scene) and accept(out):
            return out
    return None


def _moved_far(name: str, old: np.ndarray) -> Callable[[Instance], bool]:
    return lambda out: float(np.linalg.norm(xy(out.scene, name) - old)) >= MIN_MOVE


def _pair_apart(out: Instance) -> bool:
    """block2block: keep the benchmark's minimum start distance between the two blocks."""
    goal = out.goal
    if out.family != fam.BLOCK2BLOCK:
        return True
    gap = out.scene.objects[goal["block"]].distance_to(out.scene.objects[goal["target_block"]])
    return gap >= board.BLOCK2BLOCK_MIN_START_DISTANCE


@PERTURBATIONS.register("S", "S", "move a block the instruction does not involve, away from the task")
def move_distractor(instance: Instance, rng: np.random.Generator) -> Instance | None:
    base = fam.rebase(instance, instance.scene)
    if base is None:
        return None
    involved = set(fam.involved_blocks(base.goal))
    if base.family == fam.SEPARATE:  # a block touching the clump is part of the scene being separated
        involved.update(fam.neighbours(base.scene, base.goal["block"]))
    candidates = [name for name in base.scene.objects if name not in involved]
    block, target = fam.push_target(base, base.scene)
    source = xy(base.scene, block)
    keep = [xy(base.scene, name) for name in involved]

    def clear_of_task(p: np.ndarray) -> bool:
        near_path = distance_to_segment(p, source, target) < KEEP_CLEAR
        return not near_path and all(float(np.linalg.norm(p - k)) >= KEEP_CLEAR for k in keep)

    for i in rng.permutation(len(candidates)):
        name = candidates[int(i)]
        far = _moved_far(name, xy(base.scene, name))

        def accept(out: Instance, name: str = name, far=far) -> bool:
            # The goal must come out identical: e.g. a group of blocks must not gain or lose a member.
            return far(out) and clear_of_task(xy(out.scene, name)) and out.goal == base.goal

        out = _move(base, name, rng, accept, tries=MOVE_TRIES // max(1, len(candidates)))
        if out is not None:
            return out
    return None


@PERTURBATIONS.register("SB1", "SB", "move the target block to a new place")
def move_target_block(instance: Instance, rng: np.random.Generator) -> Instance | None:
    if instance.family not in (fam.BLOCK2BLOCK, fam.B2B_RELATIVE):
        return None
    name = instance.goal["target_block"]
    if name not in instance.scene.objects:
        return None
    far = _moved_far(name, xy(instance.scene, name))
    return _move(instance, name, rng, lambda out: far(out) and _pair_apart(out))


@PERTURBATIONS.register("SB2", "SB", "move the source block to a new place")
def move_source_block(instance: Instance, rng: np.random.Generator) -> Instance | None:
    name = instance.goal["block"]
    if name not in instance.scene.objects:
        return None
    if instance.family != fam.SEPARATE:
        far = _moved_far(name, xy(instance.scene, name))
        return _move(instance, name, rng, lambda out: far(out) and _pair_apart(out))
    # separate: moving the block out of the clump would leave nothing to separate, so it moves to another
    # side of the same clump, and the direction it must be pushed away in changes (by >= 60 degrees).
    avoid = [n for n in instance.goal["avoid"] if n in instance.scene.objects]
    if not avoid:
        return None
    centroid = np.mean([xy(instance.scene, n) for n in avoid], axis=0)
    old_target = fam.separate_target(instance.scene, name, avoid)

    def turned(out: Instance) -> bool:
        return float(np.linalg.norm(fam.push_target(out, out.scene)[1] - old_target)) >= MIN_MOVE

    return _move(instance, name, rng, turned, center=centroid, radius=board.SEPARATE_JOINED_DISTANCE)
