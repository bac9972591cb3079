"""The Language-Table push oracle as a policy (task: language_table, in simulation): a scripted baseline with
privileged access to the simulator's block poses."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.staging import reports_scene
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.language_table.oracle import PushOracle
from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.policies.base import PolicyArgs, PolicyError, check_tabletop

if TYPE_CHECKING:
    from lerobot.robots import Robot


def build(args: PolicyArgs, robot: Robot, task: Task, rename_map: Mapping[str, str]) -> OraclePolicy:
    check_tabletop("oracle", robot)
    if not (isinstance(task, LanguageTableTask) and reports_scene(robot)):
        raise PolicyError(
            "--policy.type=oracle solves Language-Table instructions in simulation only; "
            "use --policy.type=random or --policy.path"
        )
    return OraclePolicy(robot.read_scene, task, args.noise_std, args.language_blind)


class OraclePolicy:
    """The scripted push oracle, with privileged access to the simulator's block poses through `read_scene`.

    `noise_std` adds Gaussian noise (metres) to every action. `language_blind` is the probability,
    drawn once per episode, that the oracle ignores the words of a perturbed instruction: it then
    executes its base instance's instruction re-grounded in the current scene (and stays still
    where that instruction is already satisfied). It therefore fails ΔLB trials whose behaviour
    differs from the base, while ΔL, ΔS and ΔSB trials, whose instruction means the same as the
    base's, are unaffected.
    """

    name = "oracle"

    def __init__(
        self,
        read_scene: Callable[[], Scene],
        task: LanguageTableTask,
        noise_std: float = 0.0,
        language_blind: float = 0.0,
    ) -> None:
        if noise_std < 0:
            raise PolicyError(f"--policy.noise_std must be >= 0, got {noise_std}")
        if not 0.0 <= language_blind <= 1.0:
            raise PolicyError(f"--policy.language_blind must be a probability in [0, 1], got {language_blind}")
        self.read_scene = read_scene
        self.task = task
        self.noise_std = noise_std
        self.language_blind = language_blind
        self._oracle: PushOracle | None = None

    def reset(self, context: TrialContext) -> None:
        instance, rng = context.instance, context.rng
        goal: Instance | None = instance
        blind = rng.random() < self.language_blind
        if blind and instance.perturbation is not None:
            goal = self.task.rebase(context.base, instance.scene)
            if goal is not None and self.task.is_achieved(goal, instance.scene):
                goal = None
        self._oracle = None
        if goal is not None:
            self._oracle = PushOracle(self.task, noise_std=self.noise_std, rng=rng)
            self._oracle.reset(goal)

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]:
        if self._oracle is None:
            return {"delta_x": 0.0, "delta_y": 0.0}
        target = (observation["effector_target.x"], observation["effector_target.y"])
        dx, dy = self._oracle.act(self.read_scene(), target)
        return {"delta_x": float(dx), "delta_y": float(dy)}
