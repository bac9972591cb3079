"""The VLN perturbations (ΔL, ΔLB, ΔS, ΔSB), applied in the scene the robot left behind. Each checks its
claim against the grid planner: ΔS must leave the reference route as it was, ΔLB and ΔSB must change it."""

from __future__ import annotations

import math

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln import routes
from lerobot_contrast.domains.vln.apartment import Footprints, Route, resample
from lerobot_contrast.domains.vln.wording import name_of, paraphrase, render

PERTURBATIONS = PerturbationRegistry("vln")
MOVE_TRIES = 30
# Furniture keeps this gap to other furniture, as a person placing it would.
PLACEMENT_GAP_M = 0.05
# ΔS moves an object a short way (like the paper's, about a metre for four perturbations) and keeps it
# this far from the route, so it does not crowd the robot's way even where the shortest route is unchanged.
PASSIVE_MOVE_M = (0.3, 1.0)
KEEP_CLEAR_M = 0.3
GOAL_MOVE_M = (0.6, 1.5)


def _route(instance: Instance, scene: Scene | None = None) -> Route | None:
    goal = instance.goal
    return routes.plan(
        instance.scene if scene is None else scene, Pose.from_json(goal["start"]), goal["subgoals"], goal["radius"]
    )


@PERTURBATIONS.register("L", "L", "reword: another phrasing and other names for the same two objects")
def reword(instance: Instance, rng: np.random.Generator) -> Instance | None:
    goal = instance.goal
    new = paraphrase(goal["template"], goal["words"], goal["subgoals"], rng)
    if new is None:
        return None
    template, words = new
    return instance.derive(instruction=render(template, words), goal={**goal, "template": template, "words": words})


@PERTURBATIONS.register("LB", "LB", "change the final goal: same first subgoal, stop at another object")
def change_final_goal(instance: Instance, rng: np.random.Generator) -> Instance | None:
    base = _route(instance)
    if base is None:
        return None
    goal = instance.goal
    *passing, final = goal["subgoals"]
    candidates = [name for name in instance.scene.objects if name not in goal["subgoals"]]
    for i in rng.permutation(len(candidates)):
        name = candidates[int(i)]
        words = {**goal["words"], "final": name_of(name)}
        out = instance.derive(
            instruction=render(goal["template"], words), goal={**goal, "subgoals": [*passing, name], "words": words}
        )
        route = _route(out)
        if route is not None and routes.different_route(base, route):
            return out
    return None


@PERTURBATIONS.register("S", "S", "move a passive object, keeping it clear of the route, which stays the same")
def move_passive_object(instance: Instance, rng: np.random.Generator) -> Instance | None:
    base = _route(instance)
    passive = [name for name in instance.scene.objects if name not in instance.goal["subgoals"]]
    if base is None or not passive:
        return None
    along = resample(base.points, 0.05)
    for _ in range(MOVE_TRIES):
        name = passive[int(rng.integers(len(passive)))]
        scene = _displaced(instance.scene, name, rng, PASSIVE_MOVE_M)
        if scene is None or not routes.start_is_free(scene, Pose.from_json(instance.goal["start"])):
            continue
        if routes.distance_to_object(scene, name, along).min() < routes.ROBOT_RADIUS + KEEP_CLEAR_M:
            continue
        route = _route(instance, scene)
        if route is not None and routes.same_route(base, route):
            return instance.derive(scene=scene)
    return None


@PERTURBATIONS.register("SB", "SB", "move a subgoal object, or put an object in the way, so the route changes")
def move_goal_or_block(instance: Instance, rng: np.random.Generator) -> Instance | None:
    base = _route(instance)
    if base is None:
        return None
    strategies = [_move_goal, _block_route]
    for i in rng.permutation(len(strategies)):
        out = strategies[int(i)](instance, base, rng)
        if out is not None:
            return out
    return None


def _move_goal(instance: Instance, base: Route, rng: np.random.Generator) -> Instance | None:
    subgoals = instance.goal["subgoals"]
    for _ in range(MOVE_TRIES):
        name = subgoals[int(rng.integers(len(subgoals)))]
        scene = _displaced(instance.scene, name, rng, GOAL_MOVE_M)
        out = None if scene is None else _changed(instance, scene, base)
        if out is not None:
            return out
    return None


def _block_route(instance: Instance, base: Route, rng: np.random.Generator) -> Instance | None:
    """Put the passive object nearest to a point of the route's middle part onto that point, across it."""
    along = resample(base.points, 0.05)
    passive = [name for name in instance.scene.objects if name not in instance.goal["subgoals"]]
    for _ in range(MOVE_TRIES // 3):
        k = int(rng.integers(len(along) // 4, max(len(along) // 4 + 1, 3 * len(along) // 4)))
        point, heading = along[k], along[min(k + 1, len(along) - 1)] - along[max(k - 1, 0)]
        across = math.atan2(heading[1], heading[0]) + math.pi / 2
        nearest = sorted(passive, key=lambda n: math.dist(point, _xy(instance.scene, n)))
        for name in nearest[:3]:
            scene = instance.scene.with_object(name, Pose(float(point[0]), float(point[1]), across))
            out = _changed(instance, scene, base) if _placement_ok(scene, name) else None
            if out is not None:
                return out
    return None


def _changed(instance: Instance, scene: Scene, base: Route) -> Instance | None:
    """The instance in `scene` if the robot can still start there and the route really differs."""
    if not routes.start_is_free(scene, Pose.from_json(instance.goal["start"])):
        return None
    route = _route(instance, scene)
    if route is None or not routes.different_route(base, route):
        return None
    return instance.derive(scene=scene)


def _displaced(scene: Scene, name: str, rng: np.random.Generator, distance: tuple[float, float]) -> Scene | None:
    """`scene` with `name` moved a random `distance` (metres) in a random direction, if it fits there."""
    pose = scene.objects[name]
    step, angle = rng.uniform(*distance), rng.uniform(-math.pi, math.pi)
    moved = scene.with_object(name, Pose(pose.x + step * math.cos(angle), pose.y + step * math.sin(angle), pose.yaw))
    return moved if _placement_ok(moved, name) else None


def _placement_ok(scene: Scene, name: str) -> bool:
    """Furniture `name` stands inside the room, at least PLACEMENT_GAP_M from every other piece."""
    mine = Footprints.from_objects({name: scene.objects[name]})
    points = mine.sample_points(0)
    if routes.ROOM.wall_distance(points).min() < 0:
        return False
    others = Footprints.from_objects({n: p for n, p in scene.objects.items() if n != name})
    if len(others) == 0:
        return True
    theirs = np.concatenate([others.sample_points(i) for i in range(len(others))])
    gap = min(others.signed_distance(points).min(), mine.signed_distance(theirs).min())
    return bool(gap >= PLACEMENT_GAP_M)


def _xy(scene: Scene, name: str) -> tuple[float, float]:
    pose = scene.objects[name]
    return pose.x, pose.y
