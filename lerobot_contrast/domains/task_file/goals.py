"""Goals of task-file instances: composing instruction and goal from a template, judging the goal predicate
on a scene, and the straight-line reference path for SPL.

An instance's goal is a JSON dict: the template key, the wording (`text` with {slot} fields and the `words`
filling them), the `slots` (object or region names), the resolved `predicate` and the rendered `subgoals`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.task_file.schema import ROBOT, Predicate, Region, Template

Point = tuple[float, float]


def resolve(name: str, slots: Mapping[str, str]) -> str:
    """A goal name: "{slot}" stands for the slot's value."""
    return slots[name[1:-1]] if name.startswith("{") else name


def ground_predicate(predicate: Predicate | None, slots: Mapping[str, str]) -> dict[str, Any] | None:
    if predicate is None:
        return None
    out: dict[str, Any] = {"subject": resolve(predicate.subject, slots)}
    if predicate.region is not None:
        out["in"] = resolve(predicate.region, slots)
    else:
        out["near"] = resolve(predicate.near, slots)
        out["within"] = predicate.within
    return out


def compose(template: Template, text: str, slots: Mapping[str, str], words: Mapping[str, str]) -> tuple[str, dict]:
    """The instruction and goal for `template` worded as `text` with `slots` named by `words`."""
    goal = {
        "template": template.key,
        "text": text,
        "slots": dict(slots),
        "words": dict(words),
        "predicate": ground_predicate(template.goal, slots),
        "subgoals": [subgoal.format(**words) for subgoal in template.subgoals],
    }
    return text.format(**words), goal


def _position(scene: Scene, name: str) -> Pose | None:
    return scene.robot if name == ROBOT else scene.objects.get(name)


def holds(predicate: Mapping[str, Any] | None, scene: Scene, regions: Mapping[str, Region]) -> bool:
    """Whether the goal predicate is true in `scene` (False without a predicate, or with its subject absent)."""
    if predicate is None:
        return False
    subject = _position(scene, predicate["subject"])
    if subject is None:
        return False
    if "in" in predicate:
        return regions[predicate["in"]].contains(subject.x, subject.y)
    target = scene.objects.get(predicate["near"])
    return target is not None and subject.distance_to(target) <= predicate["within"]


def involved(goal: Mapping[str, Any], objects) -> list[str]:
    """The objects the instruction or its goal refers to, in slot order then subject, target."""
    names = list(goal["slots"].values())
    predicate = goal.get("predicate") or {}
    names += [predicate.get("subject"), predicate.get("near")]
    return [n for n in dict.fromkeys(names) if n in objects]


def goal_object(goal: Mapping[str, Any], slot: str | None, movable) -> str | None:
    """The object whose pose the goal is about: `slot`'s object, else the subject, else the target."""
    if slot is not None:
        name = goal["slots"].get(slot)
        return name if name in movable else None
    predicate = goal.get("predicate") or {}
    for name in (predicate.get("subject"), predicate.get("near")):
        if name in movable:
            return name
    return None


def target_point(predicate: Mapping[str, Any], scene: Scene, regions: Mapping[str, Region]) -> Point | None:
    if "in" in predicate:
        return regions[predicate["in"]].middle
    target = scene.objects.get(predicate["near"])
    return None if target is None else (target.x, target.y)


def waypoints(goal: Mapping[str, Any], scene: Scene, regions: Mapping[str, Region]) -> list[Point]:
    """The robot's start, the subject object (when the goal moves an object) and the goal location."""
    predicate = goal.get("predicate")
    if predicate is None:
        return []
    points = [] if scene.robot is None else [(scene.robot.x, scene.robot.y)]
    subject = _position(scene, predicate["subject"])
    if predicate["subject"] != ROBOT and subject is not None:
        points.append((subject.x, subject.y))
    target = target_point(predicate, scene, regions)
    return points if target is None else [*points, target]


def straight_line(goal: Mapping[str, Any], scene: Scene, regions: Mapping[str, Region]) -> float | None:
    points = waypoints(goal, scene, regions)
    if len(points) < 2:
        return None
    return sum(math.dist(a, b) for a, b in zip(points, points[1:], strict=False))
