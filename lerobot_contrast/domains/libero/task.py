"""LiberoTask: a LIBERO suite's tasks and init states as contrast-set instances (`--task=libero_spatial` ...),
judged by LIBERO's BDDL goal in the simulator that holds the scene."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.domains.libero import goals, judge, suites
from lerobot_contrast.domains.libero.perturbations import PERTURBATIONS

# Before the first trial the objects wait in a row beside the table, so the first staging pays for every object.
STORAGE_Y = -0.6
STORAGE_SPACING = 0.1


def family(task_id: int) -> str:
    return f"task{task_id}"


def parse_families(suite: str, families: Sequence[str] | None) -> list[int]:
    """--families=task0,task3 (or 0,3): the suite's task ids to sample; all of them when not given."""
    n = len(suites.tasks(suite))
    if not families:
        return list(range(n))
    ids = []
    for name in families:
        text = str(name).removeprefix("task")
        if not text.isdigit() or int(text) >= n:
            raise UserError(f"--families: {suite} has no task {name!r}; choose from task0 to task{n - 1}")
        ids.append(int(text))
    return ids


@dataclass(frozen=True)
class WorldChangeCost:
    """A cost model that carries objects a scene lacks to or from storage: going from one LIBERO world to another
    clears the table and sets the new one, and pays for every object of both."""

    inner: CostModel
    storage: Scene

    @property
    def name(self) -> str:
        return self.inner.name

    @property
    def unit(self) -> str:
        return self.inner.unit

    def __call__(self, current: Scene, target: Scene) -> float:
        def filled(scene: Scene) -> Scene:
            return Scene(objects={**self.storage.objects, **scene.objects}, robot=scene.robot)

        return self.inner(filled(current), filled(target))


class LiberoTask(Task):
    """One LIBERO suite: an instance is one of its tasks in one of its 50 init states."""

    suite = "libero_object"
    default_instances = 20

    def __init__(self, families: Sequence[str] | None = None) -> None:
        self.name = self.suite
        self.task_ids = parse_families(self.suite, families)
        self.perturbations = PerturbationRegistry(self.name)
        for perturbation in PERTURBATIONS:
            self.perturbations.add(perturbation)

    def instance(self, task_id: int, init_state: int, id: str | None = None) -> Instance:
        info = suites.task_info(self.suite, task_id)
        return Instance(
            id=id or f"{self.suite}-{task_id}-{init_state}",
            family=family(task_id),
            instruction=info.language,
            scene=Scene(objects=suites.init_poses(info, init_state)),
            goal={
                "suite": self.suite,
                "task_id": task_id,
                "init_state": init_state,
                "predicates": goals.goal_json(info.goal),
                "categories": dict(info.objects),
            },
        )

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` i.i.d. (task, init state) pairs, task uniform over the selected ids."""
        out = []
        for k in range(n):
            task_id = self.task_ids[int(rng.integers(len(self.task_ids)))]
            init_state = int(rng.integers(suites.task_info(self.suite, task_id).n_init_states))
            out.append(self.instance(task_id, init_state, id=f"{self.suite}-{k:04d}"))
        return out

    def storage_scene(self) -> Scene:
        names = sorted({name for task_id in self.task_ids for name in suites.task_info(self.suite, task_id).objects})
        return Scene(objects={name: Pose(STORAGE_SPACING * k, STORAGE_Y) for k, name in enumerate(names)})

    def cost_model(self, name: str) -> CostModel:
        return WorldChangeCost(super().cost_model(name), self.storage_scene())

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        """The instruction in `scene`: only where `scene` is the same LIBERO world (the same objects)."""
        world = suites.task_info(self.suite, int(instance.goal["task_id"])).objects
        if suites.world_key(scene.objects) != suites.world_key(world):
            return None
        return instance.derive(scene=scene)

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        goal = goals.goal_of(instance.goal)
        verdict = judge.holds(goal, scene)
        return goals.planar_holds(goal, scene) if verdict is None else verdict


class LiberoSpatialTask(LiberoTask):
    suite = "libero_spatial"


class LiberoObjectTask(LiberoTask):
    suite = "libero_object"


class LiberoGoalTask(LiberoTask):
    suite = "libero_goal"


class Libero10Task(LiberoTask):
    suite = "libero_10"
