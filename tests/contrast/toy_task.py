"""A one-dimensional task that implements the Task protocol, small enough to reason about costs by hand.

Object "a" must be pushed past x = +-0.1 (the instruction names the side); "b" is a distractor.
"""

from __future__ import annotations

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import Task

THRESHOLD = 0.1


class ToyTask(Task):
    name = "toy"

    def __init__(self) -> None:
        self.perturbations = PerturbationRegistry(self.name)
        self.perturbations.register("LB", "LB", "flip the side")(self._flip)
        self.perturbations.register("SB", "SB", "move a back to the middle")(self._recentre)
        self.perturbations.register("S", "S", "move the distractor")(self._move_b)

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        out = []
        for k in range(n):
            side = str(rng.choice(["left", "right"]))
            scene = Scene({"a": Pose(float(rng.uniform(-0.05, 0.05)), 0.0), "b": Pose(0.5, float(k))}, Pose(0, 0))
            out.append(Instance(f"toy-{k}", "push", f"push a {side}", scene, {"side": side}))
        return out

    def storage_scene(self) -> Scene:
        return Scene({"a": Pose(0.0, -1.0), "b": Pose(0.5, -1.0)})

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        return instance.derive(scene=scene) if "a" in scene.objects else None

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        x = scene.objects["a"].x
        return x < -THRESHOLD if instance.goal["side"] == "left" else x > THRESHOLD

    def _flip(self, instance: Instance, rng: np.random.Generator) -> Instance | None:
        side = "right" if instance.goal["side"] == "left" else "left"
        return instance.derive(instruction=f"push a {side}", goal={"side": side})

    def _recentre(self, instance: Instance, rng: np.random.Generator) -> Instance | None:
        return instance.derive(scene=instance.scene.with_object("a", Pose(0.0, 0.0)))

    def _move_b(self, instance: Instance, rng: np.random.Generator) -> Instance | None:
        b = instance.scene.objects["b"]
        return instance.derive(scene=instance.scene.with_object("b", Pose(b.x + 0.2, b.y)))
