"""LIBERO goals on our side: which objects a BDDL goal moves or names, and a planar stand-in for judging a scene that
no simulator holds (a planned, not yet staged scene); a staged scene is judged by LIBERO's own predicates."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from lerobot_contrast.contrast.scene import Scene

PLACING = ("on", "in")
# The planar stand-in counts an object as placed on or in another when their centres are this close (metres).
NEAR_M = 0.06


def owner(place: str, objects: Sequence[str]) -> str | None:
    """The object a BDDL place belongs to: `basket_1_contain_region` -> `basket_1`; None for a fixture's region."""
    if place in objects:
        return place
    matches = [name for name in objects if place.startswith(name + "_")]
    return max(matches, key=len) if matches else None


def moved_objects(goal: Sequence[Sequence[str]]) -> list[str]:
    """The objects the goal wants moved (first argument of each on/in predicate), in order."""
    return [p[1] for p in goal if p[0] in PLACING]


def named(goal: Sequence[Sequence[str]], objects: Sequence[str]) -> set[str]:
    """Every scene object the goal mentions, as the thing moved or as (the owner of) its destination."""
    out: set[str] = set()
    for predicate in goal:
        for argument in predicate[1:]:
            name = owner(argument, objects)
            if name is not None:
                out.add(name)
    return out


def planar_holds(goal: Sequence[Sequence[str]], scene: Scene) -> bool:
    """Whether every on/in predicate looks true from the planar poses alone (False for any other predicate)."""
    objects = list(scene.objects)
    for predicate in goal:
        if predicate[0] not in PLACING:
            return False
        thing, place = scene.objects.get(predicate[1]), owner(predicate[2], objects)
        if thing is None or place is None or thing.distance_to(scene.objects[place]) > NEAR_M:
            return False
    return True


def goal_json(goal: Sequence[Sequence[str]]) -> list[list[str]]:
    return [list(p) for p in goal]


def goal_of(instance_goal: Mapping) -> tuple[tuple[str, ...], ...]:
    return tuple(tuple(p) for p in instance_goal["predicates"])
