"""Hand-built Language-Table instances for the tests in this folder."""

from __future__ import annotations

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import families as fam
from lerobot_contrast.domains.language_table.wording import render

# Far corners of the sampling box, out of the way of the hand-placed blocks.
PARKING = [(0.24, -0.21), (0.24, 0.21), (0.51, -0.21), (0.51, 0.21), (0.24, 0.0), (0.51, 0.0)]


def scene(robot=(0.5, 0.2), **blocks) -> Scene:
    return Scene(objects={name: Pose(x, y, 0.0) for name, (x, y) in blocks.items()}, robot=Pose(*robot))


def make(family: str, goal: dict, words: dict, start: Scene) -> Instance:
    """An instance grounded in `start`, with its instruction rendered from `words`."""
    goal = fam.ground(family, {**goal, "words": words}, start)
    assert goal is not None, "hand-built goal must be groundable"
    return Instance(id="t-0", family=family, instruction=render(family, words), scene=start, goal=goal)


B2B_WORDS = {"verb": "push the", "block": "red moon", "preposition": "close to the", "target": "blue cube"}
ABS_WORDS = {"verb": "move the", "block": "red moon", "location": "upper left corner"}
REL_WORDS = {
    "verb": "push the",
    "block": "red moon",
    "vertical": "up",
    "horizontal": "to the left",
    "diagonal": "{v} and {h}",
    "mode": "plain",
    "slightly": None,
}
B2BREL_WORDS = {"verb": "slide the", "block": "red moon", "direction": "above the", "target": "blue cube"}
SEP_WORDS = {"template": "separate the {block} from the {avoid}", "block": "red moon", "avoid": "blue cube"}
