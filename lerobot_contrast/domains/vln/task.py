"""VLNTask: two-subgoal navigation in the studio apartment as a contrast-set Task, judged by subgoal progress."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import Judgement, Task
from lerobot_contrast.domains.vln import routes, sampler
from lerobot_contrast.domains.vln.apartment import Route, resample
from lerobot_contrast.domains.vln.examples import FAMILY, example_instances, storage_scene
from lerobot_contrast.domains.vln.perturbations import PERTURBATIONS
from lerobot_contrast.domains.vln.wording import name_of

# How close (metres from its outline) the robot must come to a subgoal object to have reached it. VLN-CE's
# 3 m would cover most of a 6 x 8 m studio; an arm's length plus the robot's size is what people mean here.
SUCCESS_RADIUS_M = 0.75
JUDGE_SPACING_M = 0.05


class VLNTask(Task):
    """Follow "go past X, then stop at Y" in the apartment: progress 0.5 for reaching X, 1.0 for stopping at Y
    after it; success is full progress. SPL and nDTW compare the path with the shortest route on the grid.

    Instances are i.i.d. furniture arrangements from the evaluation split of `sampler` (training never sees one)."""

    name = "vln"
    outcome = "subgoals"
    default_instances = 100

    def __init__(self, families: Sequence[str] | None = None, radius: float = SUCCESS_RADIUS_M) -> None:
        unknown = [f for f in families or () if f != FAMILY]
        if unknown:
            raise UserError(f"--families: unknown VLN families {unknown}; choose from: {FAMILY}")
        self.radius = radius
        self.examples = example_instances(radius)
        self.perturbations = PerturbationRegistry(self.name)
        for perturbation in PERTURBATIONS:
            self.perturbations.add(perturbation)

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` arrangements of the evaluation split, from a seed stream drawn from `rng`."""
        return sampler.sample_arrangements(n, "eval", int(rng.integers(2**31)), self.radius)

    def storage_scene(self) -> Scene:
        return storage_scene()

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        """The instruction in `scene` with the robot back at its start; None if a subgoal object is missing,
        the start pose is blocked or no route reaches the subgoals."""
        start = Pose.from_json(instance.goal["start"])
        placed = scene.with_robot(start)
        if any(name not in scene.objects for name in instance.goal["subgoals"]):
            return None
        if not routes.start_is_free(placed, start) or self._route(instance, placed) is None:
            return None
        return instance.derive(scene=placed)

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        """Whether stopping right where the robot stands in `scene` would already complete the instruction."""
        robot = scene.robot or Pose.from_json(instance.goal["start"])
        return self.judge(instance, [robot], scene).success

    def subgoals(self, instance: Instance) -> list[str]:
        return [f"the {name_of(name)}" for name in instance.goal["subgoals"]]

    def judge(self, instance: Instance, path: list[Pose], scene_after: Scene) -> Judgement:
        """Subgoals reached in order along the path; the last one counts only where the robot ended (stopped).

        Distances are measured to the furniture as staged for the episode (`instance.scene`)."""
        points = [(p.x, p.y) for p in path]
        if scene_after.robot is not None:
            points.append((scene_after.robot.x, scene_after.robot.y))
        if not points:
            start = instance.goal["start"]
            points = [(start[0], start[1])]
        reached = self._reached(instance, resample(np.array(points), JUDGE_SPACING_M))
        n = len(instance.goal["subgoals"])
        return Judgement(success=reached == n, progress=reached / n)

    def reference_route(self, instance: Instance) -> Route | None:
        return self._route(instance, instance.scene)

    def reference_length(self, instance: Instance) -> float | None:
        route = self.reference_route(instance)
        return None if route is None else route.length

    def path_metrics(self, instance: Instance, path: list[Pose]) -> dict[str, float | None]:
        return {"ndtw": self.ndtw(instance, path)}

    def ndtw(self, instance: Instance, path: list[Pose]) -> float | None:
        """nDTW of the robot's path against the reference route, normalised by the success radius."""
        route = self.reference_route(instance)
        if route is None or not path:
            return None
        return routes.ndtw(np.array([(p.x, p.y) for p in path]), route.points, self.radius)

    def _route(self, instance: Instance, scene: Scene) -> Route | None:
        start = Pose.from_json(instance.goal["start"])
        return routes.plan(scene, start, instance.goal["subgoals"], instance.goal["radius"])

    def _reached(self, instance: Instance, points: np.ndarray) -> int:
        """How many subgoals the path reached in order: each passing one from where the previous was reached,
        the last one at the path's end."""
        *passing, last = instance.goal["subgoals"]
        radius, first = instance.goal["radius"], 0
        for k, name in enumerate(passing):
            hits = np.flatnonzero(routes.distance_to_object(instance.scene, name, points[first:]) <= radius)
            if hits.size == 0:
                return k
            first += int(hits[0])
        return len(passing) + int(routes.distance_to_object(instance.scene, last, points[-1:])[0] <= radius)


class VLNPaperTask(VLNTask):
    """The paper's design: the five participants' arrangements (`examples.ARRANGEMENTS`), one instance each."""

    name = "vln_paper"
    default_instances = 5

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` of the shipped instances (one per furniture arrangement), in a random order."""
        if not 1 <= n <= len(self.examples):
            raise UserError(
                f"--n_instances: the VLN paper set has {len(self.examples)} instances (one per furniture "
                f"arrangement); use --n_instances between 1 and {len(self.examples)}, got {n}"
            )
        return [self.examples[int(i)] for i in rng.permutation(len(self.examples))[:n]]
