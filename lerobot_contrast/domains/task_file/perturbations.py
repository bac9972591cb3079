"""The generic perturbations a task file parameterises: paraphrase (ΔL); swap referents, flip, change the
goal (ΔLB); move a distractor, add or remove a distractor (ΔS); move the goal object (ΔSB).

Each factory takes the task (a `Composer`: the FileTask) and the perturbation's parameters and returns `apply(instance, rng)`, which
gets the instance set in the scene the robot left behind and returns the perturbed instance or None.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbFn
from lerobot_contrast.contrast.scene import Pose, Scene, distance_to_segment
from lerobot_contrast.domains.task_file.goals import goal_object, involved, waypoints
from lerobot_contrast.domains.task_file.schema import TaskSpec, Template
from lerobot_contrast.domains.task_file.wording import pick, substitute
from lerobot_contrast.domains.task_file.world import free_pose


class Composer(Protocol):
    """What the perturbations need of the task file's task: its spec, and re-wording an instance."""

    spec: TaskSpec

    def template_of(self, instance: Instance) -> Template: ...

    def compose(self, instance: Instance, *, slots=None, words=None, text=None) -> Instance: ...


PARAPHRASE_TRIES = 50


def paraphrase(task: Composer, synonyms) -> PerturbFn:
    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        template = task.template_of(instance)
        for _ in range(PARAPHRASE_TRIES):
            text = substitute(pick(rng, template.texts), synonyms, rng)
            words = {slot: pick(rng, task.spec.words(value)) for slot, value in instance.goal["slots"].items()}
            out = task.compose(instance, text=text, words=words)
            if out.instruction != instance.instruction:
                return out
        return None

    return apply


def swap_pairs(template, slots: tuple[str, str] | None) -> list[tuple[str, str]]:
    """Pairs of slots whose values may trade places: same kind, sharing at least two candidates."""
    names = list(template.slots)
    pairs = [slots] if slots else [(a, b) for i, a in enumerate(names) for b in names[i + 1 :]]
    out = []
    for a, b in pairs:
        sa, sb = template.slots.get(a), template.slots.get(b)
        if sa and sb and sa.kind == sb.kind and len(set(sa.candidates) & set(sb.candidates)) >= 2:
            out.append((a, b))
    return out


def swap_referents(task: Composer, slots: tuple[str, str] | None) -> PerturbFn:
    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        template, goal = task.template_of(instance), instance.goal
        for a, b in swap_pairs(template, slots):
            va, vb = goal["slots"][a], goal["slots"][b]
            if va in template.slots[b].candidates and vb in template.slots[a].candidates:
                words = {a: goal["words"][b], b: goal["words"][a]}
                out = task.compose(instance, slots={a: vb, b: va}, words=words)
                if out.goal["predicate"] != goal["predicate"] or goal["predicate"] is None:
                    return out
        return None

    return apply


def _same_index_word(task: Composer, old: str, word: str, new: str) -> str:
    """The new referent's word at the index the old word had (its plain word where it has fewer)."""
    old_words, new_words = task.spec.words(old), task.spec.words(new)
    i = old_words.index(word) if word in old_words else 0
    return new_words[i] if i < len(new_words) else new_words[0]


def flip(task: Composer, pairs: tuple[tuple[str, str], ...]) -> PerturbFn:
    opposite = {a: b for a, b in pairs} | {b: a for a, b in pairs}

    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        template, goal = task.template_of(instance), instance.goal
        slots, words = {}, {}
        for name, value in goal["slots"].items():
            new = opposite.get(value)
            if new is not None and new in template.slots[name].candidates and new not in goal["slots"].values():
                slots[name], words[name] = new, _same_index_word(task, value, goal["words"][name], new)
        return task.compose(instance, slots=slots, words=words) if slots else None

    return apply


def change_goal(task: Composer, slot: str | None) -> PerturbFn:
    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        template, goal = task.template_of(instance), instance.goal
        names = [slot] if slot else list(template.slots)
        for i in rng.permutation(len(names)):
            name = names[int(i)]
            if name not in template.slots:
                continue
            options = [
                v
                for v in template.slots[name].candidates
                if v not in goal["slots"].values() and (v in task.spec.workspace.regions or v in instance.scene.objects)
            ]
            if options:
                new = pick(rng, options)
                words = {name: _same_index_word(task, goal["slots"][name], goal["words"][name], new)}
                return task.compose(instance, slots={name: new}, words=words)
        return None

    return apply


def _clear_of_task(task: Composer, instance: Instance, clearance: float) -> Callable[[Pose], bool]:
    """Away from the objects the instruction involves, the goal region and the straight path to the goal."""
    scene, goal = instance.scene, instance.goal
    keep = [scene.objects[n] for n in involved(goal, scene.objects)]
    points = waypoints(goal, scene, task.spec.workspace.regions)
    segments = list(zip(points, points[1:], strict=False))
    region = (goal.get("predicate") or {}).get("in")

    def accept(pose: Pose) -> bool:
        p = (pose.x, pose.y)
        if region is not None and task.spec.workspace.regions[region].contains(*p):
            return False
        if any(distance_to_segment(p, a, b) < clearance for a, b in segments):
            return False
        return all(pose.distance_to(k) >= clearance for k in keep)

    return accept


def _distractors(task: Composer, instance: Instance) -> list[str]:
    """Movable objects in the scene that the instruction does not involve (objects the file does not declare,
    reported by a robot's perception, are left alone)."""
    busy = set(involved(instance.goal, task.spec.objects))
    movable = {n for n, o in task.spec.objects.items() if o.movable}
    return [n for n in instance.scene.objects if n in movable and n not in busy]


def move_distractor(task: Composer, min_move: float, clearance: float) -> PerturbFn:
    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        candidates, clear = _distractors(task, instance), _clear_of_task(task, instance, clearance)
        for i in rng.permutation(len(candidates)):
            name = candidates[int(i)]
            old = instance.scene.objects[name]
            pose = free_pose(
                task.spec, name, instance.scene, rng, lambda p, o=old: p.distance_to(o) >= min_move and clear(p)
            )
            if pose is not None:
                return instance.derive(scene=instance.scene.with_object(name, pose))
        return None

    return apply


def _without(scene: Scene, name: str) -> Scene:
    return Scene({n: p for n, p in scene.objects.items() if n != name}, scene.robot)


def add_remove_distractor(task: Composer, mode: str, clearance: float) -> PerturbFn:
    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        scene = instance.scene
        options: list[tuple[str, str]] = []
        if mode in ("add", "either"):
            options += [("add", n) for n, o in task.spec.objects.items() if o.movable and n not in scene.objects]
        if mode in ("remove", "either"):
            options += [("remove", n) for n in _distractors(task, instance)]
        clear = _clear_of_task(task, instance, clearance)
        for i in rng.permutation(len(options)):
            action, name = options[int(i)]
            if action == "remove":
                return instance.derive(scene=_without(scene, name))
            pose = free_pose(task.spec, name, scene, rng, clear)
            if pose is not None:
                return instance.derive(scene=scene.with_object(name, pose))
        return None

    return apply


def move_goal_object(task: Composer, slot: str | None, min_move: float) -> PerturbFn:
    movable = {n for n, o in task.spec.objects.items() if o.movable}

    def apply(instance: Instance, rng: np.random.Generator) -> Instance | None:
        name = goal_object(instance.goal, slot, movable)
        if name is None or name not in instance.scene.objects:
            return None
        old = instance.scene.objects[name]

        def accept(pose: Pose) -> bool:
            moved = instance.derive(scene=instance.scene.with_object(name, pose))
            return pose.distance_to(old) >= min_move and not task.is_achieved(moved, moved.scene)

        pose = free_pose(task.spec, name, instance.scene, rng, accept)
        return None if pose is None else instance.derive(scene=instance.scene.with_object(name, pose))

    return apply


GENERIC: dict[str, tuple[str, Callable[..., PerturbFn], str]] = {
    "paraphrase": ("L", paraphrase, "reword with synonyms; same goal"),
    "swap_referents": ("LB", swap_referents, "swap two referents of the instruction"),
    "flip": ("LB", flip, "flip direction or region words to their opposites"),
    "change_goal": ("LB", change_goal, "ask for another goal object or region"),
    "move_distractor": ("S", move_distractor, "move an object the instruction does not involve"),
    "add_remove_distractor": ("S", add_remove_distractor, "add or remove an object the instruction does not involve"),
    "move_goal_object": ("SB", move_goal_object, "move the object the goal is about"),
}


def custom_kwargs(fn: Callable, params: Mapping[str, Any], task: Composer) -> dict[str, Any]:
    """A custom perturbation's keyword arguments: its params, plus the task when it takes a `task` argument."""
    wants_task = "task" in inspect.signature(fn).parameters
    return {**params, "task": task} if wants_task else dict(params)


def build(task: Composer, kind: str, params: dict[str, Any]) -> PerturbFn:
    return GENERIC[kind][1](task, **params)
