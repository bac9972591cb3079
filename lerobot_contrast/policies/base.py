"""The policy interface the runner drives, and the `--policy.*` settings every registered policy is built from.

A policy maps a robot observation (LeRobot's flat dict) to a robot action dict."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import TrialContext

if TYPE_CHECKING:
    from lerobot.robots import Robot


class Policy(Protocol):
    name: str

    def reset(self, context: TrialContext) -> None:
        """Start an episode of `context.instance`; `context.rng` is this trial's own randomness."""
        ...

    def act(self, observation: Mapping[str, Any]) -> dict[str, float]: ...


class PolicyError(UserError):
    pass


# Builds a policy for one robot and task from the --policy.* settings and --rename_map.
Builder = Callable[["PolicyArgs", Any, Task, Mapping[str, str]], Policy]


# The policy an evaluation runs when neither --policy.path nor --policy.type is given.
DEFAULT_POLICY = "tabletop_pointer"


@dataclass
class PolicyArgs:
    # A LeRobot policy to load: a directory written by save_pretrained, or a Hub repo id.
    path: str | None = None
    # Without --policy.path: a registered policy (tabletop_pointer: the learned pixel policy whose weights ship;
    # oracle: scripted push oracle with privileged state; random; route_follower: scripted VLN navigator;
    # so101_demonstrator: the virtual SO-101's scripted demonstrator), or a LeRobot policy type built fresh with
    # random weights from the robot's features (for smoke tests).
    type: str | None = field(default=None, metadata={"help_default": DEFAULT_POLICY})
    # Torch device for a LeRobot policy (cpu, cuda, mps); default: the policy config's own.
    device: str | None = None
    # Automatic mixed precision for a LeRobot policy on CUDA.
    use_amp: bool = False
    # Gaussian noise added to each action of the oracle or a LeRobot policy (the learned default included), in
    # the action's units: metres on the simulated tabletop (0 = none). It makes a noisier copy of a policy.
    noise_std: float = 0.0
    # A registered policy's own settings, e.g. so101_demonstrator's '{placement: ADDRESS the twin printed}'.
    options: dict[str, str] = field(default_factory=dict)
    # Probability per episode that the oracle ignores a perturbed instruction's words and executes
    # its base instruction instead (0 = reads every instruction).
    language_blind: float = 0.0


# The planar end-effector deltas of the simulated tabletop, which the scripted tabletop baselines send.
TABLETOP_ACTIONS = {"delta_x", "delta_y"}


def check_tabletop(name: str, robot: Robot) -> None:
    if set(robot.action_features) != TABLETOP_ACTIONS:
        raise PolicyError(
            f"--policy.type={name} drives the simulated tabletop only; give --policy.path for {robot.name}"
        )
