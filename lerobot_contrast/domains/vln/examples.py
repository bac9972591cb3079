"""The shipped example evaluation set: five furniture arrangements of the studio, each with a start pose and
a two-subgoal instruction, in the shape of the paper's real-robot study (five participants' set-ups)."""

from __future__ import annotations

import math

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln.apartment.furniture import STUDIO
from lerobot_contrast.domains.vln.wording import name_of, render

FAMILY = "two_subgoals"
HALF_PI = math.pi / 2

# Each participant's arrangement moves a few pieces of the furnished studio (`STUDIO`), so restaging costs
# metres, not the whole room. Each lists the furniture it moves (x, y, yaw), the robot's start pose, the two
# subgoal objects and the participant's phrasing of the route.
ARRANGEMENTS: tuple[dict, ...] = (
    {
        "moved": {"lamp": (4.1, 3.5, 0.0), "table": (5.2, 1.9, 0.0), "chair": (5.2, 1.1, 0.0)},
        "start": (7.0, 1.0, math.pi),
        "subgoals": ("lamp", "bookshelf"),
        "template": "Go pass by the {first}, keep going and stop when you reach the {final}.",
    },
    {
        "moved": {
            "table": (3.0, 1.5, 0.0),
            "chair": (3.0, 2.3, 0.0),
            "lamp": (5.8, 3.2, 0.0),
            "couch": (2.4, 4.1, 0.0),
        },
        "start": (7.2, 1.2, HALF_PI),
        "subgoals": ("table", "bed"),
        "template": "Walk over to the {first}, then turn and stop in front of the {final}.",
    },
    {
        "moved": {"plant": (7.5, 0.5, 0.0), "couch": (3.4, 3.0, HALF_PI), "lamp": (1.4, 4.4, 0.0)},
        "start": (1.0, 1.0, 0.0),
        "subgoals": ("plant", "couch"),
        "template": "Head over to the {first} in the far corner and then go stop next to the {final}.",
    },
    {
        "moved": {"tv_stand": (7.7, 3.2, HALF_PI), "dresser": (7.7, 1.3, HALF_PI), "desk": (2.6, 5.7, 0.0)},
        "start": (2.8, 2.0, 0.0),
        "subgoals": ("tv_stand", "desk"),
        "template": "Go by the {first} and stop when you get to the {final}.",
    },
    {
        "moved": {"chair": (3.6, 2.2, 0.0), "dresser": (0.3, 4.4, HALF_PI), "table": (3.8, 1.2, 0.0)},
        "start": (6.8, 2.6, math.pi),
        "subgoals": ("chair", "dresser"),
        "template": "Move towards the {first}, then go to the {final} and stop there.",
    },
)


def _scene(objects: dict[str, tuple[float, float, float]], robot: tuple[float, float, float] | None) -> Scene:
    return Scene(
        objects={name: Pose(*pose) for name, pose in objects.items()},
        robot=None if robot is None else Pose(*robot),
    )


def storage_scene() -> Scene:
    """The studio before the first trial: as furnished, which no arrangement leaves unchanged."""
    return _scene(STUDIO, None)


def example_instances(radius: float) -> list[Instance]:
    """The five shipped instances, ids vln-1 ... vln-5; a subgoal is reached within `radius` of its outline."""
    out = []
    for k, arrangement in enumerate(ARRANGEMENTS, start=1):
        first, final = arrangement["subgoals"]
        words = {"first": name_of(first), "final": name_of(final)}
        out.append(
            Instance(
                id=f"vln-{k}",
                family=FAMILY,
                instruction=render(arrangement["template"], words),
                scene=_scene({**STUDIO, **arrangement["moved"]}, arrangement["start"]),
                goal={
                    "subgoals": [first, final],
                    "start": list(arrangement["start"]),
                    "radius": radius,
                    "template": arrangement["template"],
                    "words": words,
                },
            )
        )
    return out
