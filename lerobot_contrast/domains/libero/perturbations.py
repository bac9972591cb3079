"""The four contrast axes on LIBERO scenes: paraphrase (ΔL), another object (ΔLB), a moved distractor (ΔS) and the
goal's own object moved (ΔSB). Each returns None where it does not apply to the instance in its current scene."""

from __future__ import annotations

import math
import re

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import Perturbation
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.libero import goals, wording

# Scene moves: how far an object is carried (metres), and the footprint radius that keeps it clear of the others.
MOVE_M = (0.05, 0.10)
RADIUS_M = {"basket": 0.11, "plate": 0.09, "wooden_tray": 0.12, "chefmate_8_frypan": 0.1, "moka_pot": 0.06}
DEFAULT_RADIUS_M = 0.045
GAP_M = 0.01
TRIES = 40


def _goal(instance: Instance) -> tuple[tuple[str, ...], ...]:
    return goals.goal_of(instance.goal)


def _category(instance: Instance, name: str) -> str:
    return instance.goal["categories"][name]


def paraphrase(instance: Instance, rng: np.random.Generator) -> Instance | None:
    """Reword verbs and prepositions with synonyms; the BDDL goal stays."""
    text = instance.instruction
    usable = [(pattern, options) for pattern, options in wording.SYNONYMS if wording.find(text, pattern)]
    if not usable:
        return None
    for k in rng.permutation(len(usable))[:2]:
        pattern, options = usable[int(k)]
        text = re.sub(rf"\b{pattern}\b", options[int(rng.integers(len(options)))], text, count=1)
    return instance.derive(instruction=text) if text != instance.instruction else None


def other_object(instance: Instance, rng: np.random.Generator) -> Instance | None:
    """Name another object of the scene in place of one the goal moves; the goal moves that object instead."""
    goal = _goal(instance)
    moved = goals.moved_objects(goal)
    if not moved:
        return None
    old = moved[int(rng.integers(len(moved)))]
    said = wording.mention(instance.instruction, _category(instance, old))
    named = goals.named(goal, list(instance.scene.objects))
    taken = {_category(instance, name) for name in named}
    counts: dict[str, int] = {}
    for name in instance.scene.objects:
        counts[_category(instance, name)] = counts.get(_category(instance, name), 0) + 1
    choices = [
        name
        for name in instance.scene.objects
        if name not in named
        and _category(instance, name) not in taken
        and counts[_category(instance, name)] == 1
        and wording.mention(instance.instruction, _category(instance, name)) is None  # not already a landmark
    ]
    if said is None or not choices:
        return None
    new = choices[int(rng.integers(len(choices)))]
    text = wording.replace_first(instance.instruction, said, wording.phrase(_category(instance, new)))
    predicates = [[new if arg == old else arg for arg in p] for p in goal]
    return instance.derive(instruction=text, goal={**instance.goal, "predicates": predicates})


def free_spot(scene: Scene, name: str, radius: dict[str, float], rng: np.random.Generator) -> Pose | None:
    """A place MOVE_M away from `name`'s pose, inside the area the objects span and clear of every other object."""
    xs = [p.x for p in scene.objects.values()]
    ys = [p.y for p in scene.objects.values()]
    here = scene.objects[name]
    for _ in range(TRIES):
        distance, angle = rng.uniform(*MOVE_M), rng.uniform(0.0, 2.0 * math.pi)
        x, y = here.x + distance * math.cos(angle), here.y + distance * math.sin(angle)
        if not (min(xs) <= x <= max(xs) and min(ys) <= y <= max(ys)):
            continue
        clear = all(
            math.hypot(x - p.x, y - p.y) >= radius[name] + radius[other] + GAP_M
            for other, p in scene.objects.items()
            if other != name
        )
        if clear:
            return Pose(x, y, here.yaw)
    return None


def _move(instance: Instance, names: list[str], rng: np.random.Generator) -> Instance | None:
    radius = {n: RADIUS_M.get(_category(instance, n), DEFAULT_RADIUS_M) for n in instance.scene.objects}
    for k in rng.permutation(len(names)):
        spot = free_spot(instance.scene, names[int(k)], radius, rng)
        if spot is not None:
            return instance.derive(scene=instance.scene.with_object(names[int(k)], spot))
    return None


def move_distractor(instance: Instance, rng: np.random.Generator) -> Instance | None:
    """Carry an object the goal does not mention to a free place nearby."""
    named = goals.named(_goal(instance), list(instance.scene.objects))
    return _move(instance, [n for n in instance.scene.objects if n not in named], rng)


def move_goal_object(instance: Instance, rng: np.random.Generator) -> Instance | None:
    """Carry the object the goal moves (or the object it is to be placed on or in) to a free place nearby."""
    goal = _goal(instance)
    objects = list(instance.scene.objects)
    targets = {n for p in goal if p[0] in goals.PLACING for n in (p[1], goals.owner(p[2], objects)) if n in objects}
    return _move(instance, sorted(targets), rng)


PERTURBATIONS = (
    Perturbation("L", "L", paraphrase, "reword the instruction with synonyms; same BDDL goal"),
    Perturbation("LB", "LB", other_object, "name another object of the scene; the goal moves it instead"),
    Perturbation("S", "S", move_distractor, "move an object the goal does not mention to a free place"),
    Perturbation("SB", "SB", move_goal_object, "move the object the goal moves, or its destination"),
)
