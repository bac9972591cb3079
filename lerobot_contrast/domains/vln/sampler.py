"""I.i.d. furniture arrangements of the studio, made the way the paper's participants made theirs: move a few
pieces to free, reachable places, pick a start pose and two subgoal objects with a route through both, and
phrase it with a template.

Training and evaluation never share an arrangement: each arrangement's key (its furniture, start and subgoals)
hashes to one split, and a sampler for one split rejects the other's. Evaluation draws from its own seed stream
(`EVAL_STREAM`), training from `TRAIN_STREAM`, so the two also never draw the same sequence of candidates.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln import routes
from lerobot_contrast.domains.vln.apartment import STUDIO, Footprints, clearance, furniture_for
from lerobot_contrast.domains.vln.examples import FAMILY
from lerobot_contrast.domains.vln.perturbations import _placement_ok
from lerobot_contrast.domains.vln.wording import TEMPLATES, name_of, render

SPLITS = ("train", "eval")
TRAIN_STREAM, EVAL_STREAM = 260_001, 260_002
# The most instances one call makes, and the candidates it may try for one arrangement before giving up.
MAX_INSTANCES = 5_000
MAX_TRIES = 400
# Participants moved two to four pieces; a piece stays this far from the walls' inside so the robot can pass.
MOVED = (2, 4)
WALL_MARGIN_M = 0.1
# A route this short is no navigation; the start must not already be at the first subgoal.
MIN_ROUTE_M = 1.5


def arrangement_key(instance: Instance) -> str:
    """What makes an arrangement itself: its furniture, the start pose and the two subgoals."""
    objects = routes.objects_key(instance.scene.objects)
    start = tuple(round(v, 3) for v in instance.goal["start"])
    return repr((objects, start, tuple(instance.goal["subgoals"])))


def split_of(instance: Instance) -> str:
    digest = hashlib.blake2b(arrangement_key(instance).encode(), digest_size=8).digest()
    return SPLITS[digest[0] & 1]


def _move_pieces(rng: np.random.Generator) -> Scene | None:
    scene = Scene(objects={name: Pose(*pose) for name, pose in STUDIO.items()})
    names = sorted(STUDIO)
    for i in rng.choice(len(names), size=int(rng.integers(MOVED[0], MOVED[1] + 1)), replace=False):
        name = names[int(i)]
        for _ in range(30):
            x = rng.uniform(WALL_MARGIN_M, routes.ROOM.size_x - WALL_MARGIN_M)
            y = rng.uniform(WALL_MARGIN_M, routes.ROOM.size_y - WALL_MARGIN_M)
            moved = scene.with_object(name, Pose(x, y, float(rng.integers(4)) * math.pi / 2))
            if _fits(moved, name):
                scene = moved
                break
        else:
            return None
    return scene


def _fits(scene: Scene, name: str) -> bool:
    """Whether `name` stands clear of the rest: bounding circles decide most cases, `_placement_ok` the others."""
    here = scene.objects[name]
    mine = furniture_for(name)
    outer, inner = math.hypot(mine.length, mine.width) / 2, min(mine.length, mine.width) / 2
    undecided = False
    for other, pose in scene.objects.items():
        if other == name:
            continue
        kind = furniture_for(other)
        gap = math.hypot(pose.x - here.x, pose.y - here.y)
        if gap < inner + min(kind.length, kind.width) / 2:
            return False
        undecided |= gap < outer + math.hypot(kind.length, kind.width) / 2 + 0.05
    if undecided:
        return _placement_ok(scene, name)
    return bool(routes.ROOM.wall_distance(np.array([here.x, here.y])) >= outer)  # clear of the walls too


def _start(scene: Scene, rng: np.random.Generator) -> Pose | None:
    footprints = Footprints.from_objects(scene.objects)  # not the planner's grid: most candidates fail before it
    for _ in range(30):
        x, y = rng.uniform(0.3, routes.ROOM.size_x - 0.3), rng.uniform(0.3, routes.ROOM.size_y - 0.3)
        if clearance(routes.ROOM, footprints, np.array([x, y]))[0] >= routes.ROBOT_RADIUS:
            return Pose(x, y, rng.uniform(-math.pi, math.pi))
    return None


def _candidate(rng: np.random.Generator, radius: float, ident: str, split: str) -> Instance | None:
    """One candidate arrangement of `split`, or None where it fails a check (cheap checks first)."""
    scene = _move_pieces(rng)
    start = None if scene is None else _start(scene, rng)
    if scene is None or start is None:
        return None
    first, final = (str(n) for n in rng.choice(sorted(scene.objects), size=2, replace=False))
    template = TEMPLATES[int(rng.integers(len(TEMPLATES)))]
    words = {"first": name_of(first), "final": name_of(final)}
    instance = Instance(
        id=ident,
        family=FAMILY,
        instruction=render(template, words),
        scene=scene.with_robot(start),
        goal={
            "subgoals": [first, final],
            "start": [start.x, start.y, start.yaw],
            "radius": radius,
            "template": template,
            "words": words,
        },
    )
    if split_of(instance) != split:
        return None
    if routes.distance_to_object(scene, first, np.array([[start.x, start.y]]))[0] <= radius + 0.5:
        return None
    route = routes.plan(scene, start, [first, final], radius)
    return None if route is None or route.length < MIN_ROUTE_M else instance


def arrangement(split: str, base: int, index: int, radius: float) -> Instance:
    """Arrangement `index` of the stream `base` in `split`; a one-line UserError if none can be placed."""
    stream = TRAIN_STREAM if split == "train" else EVAL_STREAM
    rng = np.random.default_rng([stream, base, index])
    for _ in range(MAX_TRIES):
        instance = _candidate(rng, radius, f"vln-{split}-{base % 10_000}-{index}", split)
        if instance is not None:
            return instance
    raise UserError(
        f"--task=vln: could not place the furniture of arrangement {index} in {MAX_TRIES} tries (the sampler "
        "moves 2-4 pieces to free, reachable places); try another --seed"
    )


def sample_arrangements(n: int, split: str, base: int, radius: float) -> list[Instance]:
    """`n` arrangements of `split` ("train" or "eval") from the seed stream `base`."""
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
    if not 1 <= n <= MAX_INSTANCES:
        raise UserError(
            f"--n_instances: the VLN arrangement sampler makes 1 to {MAX_INSTANCES} instances per run, got {n}"
        )
    return [arrangement(split, base, k, radius) for k in range(n)]
