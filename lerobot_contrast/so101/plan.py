"""What the demonstrator does for an instruction: its goal (matched against the task file's own templates), where
the object goes, the joint goals that take it there (inverse kinematics on the arm's model), and each episode's placement.
The demonstrator plans with it, and so does the arm when it stages a trial itself."""

from __future__ import annotations

import itertools
import logging
import math
from collections.abc import Mapping

import mujoco
import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.task_file import FileTask, TaskSpec
from lerobot_contrast.domains.task_file.goals import compose
from lerobot_contrast.domains.task_file.schema import Region
from lerobot_contrast.domains.task_file.world import sample_scene
from lerobot_contrast.so101 import arm, reach
from lerobot_contrast.so101.scene import build_spec, is_bin, object_sizes

NEAR_GAP = 0.012  # m between the faces of an object put next to another: room for where it lands, within the goal
BIN_INSETS = (0.0, 0.015, 0.03)  # m towards the arm from a bin's middle, tried in turn when the middle is unreachable
BIN_SIDESTEP = 0.03  # m from a bin's middle: the spots around it, for a bin that already holds an object


def _plain(text: str) -> str:
    return " ".join(text.lower().replace(".", " ").split())


def goal_of(task: FileTask, instruction: str) -> dict:
    """The goal predicate of `instruction`: the template, wording and slots whose rendering it is."""
    wanted, spec, example = _plain(instruction), task.spec, None
    for template in spec.templates.values():
        names = list(template.slots)
        for values in itertools.product(*(template.slots[n].candidates for n in names)):
            if len(set(values)) < len(values):
                continue
            slots = dict(zip(names, values, strict=True))
            for text in template.texts:
                for said in itertools.product(*(spec.words(v) for v in values)):
                    rendered, goal = compose(template, text, slots, dict(zip(names, said, strict=True)))
                    example = example or rendered
                    if _plain(rendered) == wanted:
                        return goal["predicate"]
    raise UserError(
        f"the instruction {instruction!r} is none of task {spec.name}'s; say it as its templates do, e.g. {example!r}"
    )


def arm_model(spec: TaskSpec) -> mujoco.MjModel:
    """The twin's world as the twin builds it: the arm where the twin has it, for the inverse kinematics."""
    return build_spec(spec).compile()


def targets(predicate: Mapping, poses: Mapping[str, tuple], spec: TaskSpec) -> list[tuple[float, float]]:
    """Where to put the subject down, best first: in a bin, clear of what it already holds, or beside the base object
    across one of its faces, clear of the other objects and of the bins' walls and on the workspace (a base at its
    edge is not put beside on the far side, where no camera checks the table), nearest the subject first."""
    regions = spec.workspace.regions
    subject = predicate["subject"]
    others = [(x, y) for name, (x, y, _, _) in poses.items() if name not in (subject, predicate.get("near"))]
    if "in" in predicate:
        return _in_bin(regions[predicate["in"]], others, spec.workspace.min_spacing)
    base = predicate["near"]
    sizes = object_sizes(spec)
    bx, by, _, byaw = poses[base]
    distance = (sizes[subject] + sizes[base]) / 2 + NEAR_GAP
    spots = [(bx + distance * math.cos(h), by + distance * math.sin(h)) for h in reach.headings(byaw)]
    walls = [(r.center, r.radius + sizes[subject]) for r in regions.values() if is_bin(r)]
    (x0, x1), (y0, y1) = spec.workspace.area.box
    half = sizes[subject] / 2
    clear = [
        s
        for s in spots
        if x0 + half <= s[0] <= x1 - half
        and y0 + half <= s[1] <= y1 - half
        and all(math.dist(s, o) >= spec.workspace.min_spacing for o in others)
        and all(math.dist(s, centre) >= reach_out for centre, reach_out in walls)
    ]
    sx, sy = poses[subject][:2]
    return sorted(clear, key=lambda s: math.dist(s, (sx, sy)))


def _in_bin(region: Region, others: list[tuple[float, float]], spacing: float) -> list[tuple[float, float]]:
    """Spots in a bin, best first: its middle, then nearer the arm (where the middle is out of reach), then around
    the middle; those `spacing` clear of every other object before the rest (a cube dropped against one already in
    the bin jams both against its wall, where the jaws cannot take either out), the most clear first."""
    cx, cy = region.middle
    reach_out = math.hypot(cx, cy)
    spots = [(cx * (1 - inset / reach_out), cy * (1 - inset / reach_out)) for inset in BIN_INSETS]
    spots += [
        (cx + BIN_SIDESTEP * math.cos(a), cy + BIN_SIDESTEP * math.sin(a))
        for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)
    ]

    def room(spot: tuple[float, float]) -> float:
        return min((math.dist(spot, other) for other in others), default=math.inf)

    clear = [spot for spot in spots if room(spot) >= spacing]
    return clear + sorted((spot for spot in spots if room(spot) < spacing), key=room, reverse=True)


def ik_seeds(x: float, y: float) -> list[dict[str, float]]:
    """Joint angles to start the inverse kinematics from: rest, then rest turned towards the object (at the edge of
    the arm's reach the solution found depends on where the search starts)."""
    return [dict(arm.REST), {**arm.REST, "shoulder_pan": math.atan2(y, x)}]


def waypoints(model: mujoco.MjModel, predicate: Mapping, poses: Mapping[str, tuple], spec: TaskSpec):
    """The pick-and-place joint goals from rest for the first reachable target; Unreachable when none is."""
    subject = predicate["subject"]
    size = object_sizes(spec)[subject]
    for target, seed in itertools.product(targets(predicate, poses, spec), ik_seeds(*poses[subject][:2])):
        try:
            return reach.pick_and_place(model, seed, poses[subject], size, target)
        except reach.Unreachable:
            continue
    raise reach.Unreachable(f"no reachable place to put {subject} for {predicate}")


def placement(spec: TaskSpec, seed: int, episode: int) -> dict[str, tuple[float, float, float]]:
    """Episode `episode`'s placement of the evaluation set's objects (x, y, yaw): in their areas, apart by the task's
    spacing, turned at random (a cube looks the same every quarter turn)."""
    rng = np.random.default_rng([seed, episode])
    scene = sample_scene(spec, rng)
    if scene is None:
        raise UserError(f"task {spec.name}: its objects do not fit apart in their areas; widen them")
    movable = [name for name in scene.objects if spec.objects[name].movable]
    return {
        name: (scene.objects[name].x, scene.objects[name].y, rng.uniform(-math.pi / 4, math.pi / 4)) for name in movable
    }


def schedule(model: mujoco.MjModel, predicate: Mapping, poses: Mapping[str, tuple], spec: TaskSpec, pace: float):
    """Each motion's end (seconds from the start, times `pace`) with its joint goals; empty (stay at rest, with a
    warning) when nothing reachable does the task."""
    try:
        steps = waypoints(model, predicate, poses, spec)
    except reach.Unreachable as error:
        where = {name: [round(value, 3) for value in pose] for name, pose in poses.items()}
        logging.warning("so101_demo: episode left at rest: %s; the objects (x, y, z, yaw): %s", error, where)
        steps = []
    end, timed = 0.0, []
    for step in steps:
        end += step.seconds * pace
        timed.append((end, dict(step.goals)))
    return timed


def goals_at(timed: list[tuple[float, dict[str, float]]], elapsed: float) -> dict[str, float]:
    """The joint goals (LeRobot's degrees) `elapsed` seconds into the schedule: rest before and after."""
    goals = next((goals for end, goals in timed if elapsed < end), arm.REST)
    return {f"{name}.pos": arm.to_lerobot(name, goals[name]) for name in arm.MOTOR_NAMES}
