"""Every policy an evaluation can run, by name, behind one registry: the scripted baselines (each says the task
it solves) and any LeRobot `PreTrainedPolicy`, loaded from --policy.path or from a checkpoint an entry names."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import import_module
from importlib.util import find_spec
from pathlib import Path
from typing import TYPE_CHECKING

from lerobot_contrast.contrast.task import Task
from lerobot_contrast.policies.action_noise import NoisyPolicy
from lerobot_contrast.policies.base import DEFAULT_POLICY, Builder, Policy, PolicyArgs, PolicyError

if TYPE_CHECKING:
    from lerobot.robots import Robot

PRETRAINED_BUILD = "lerobot_contrast.policies.pretrained:build"


def _shipped_weights(package: str) -> str:
    """The `weights/` directory a policy plugin ships, found without importing it (and so torch)."""
    spec = find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        raise ImportError(f"{package} is not installed; run scripts/setup.sh")
    return str(Path(next(iter(spec.submodule_search_locations))) / "weights")


@dataclass(frozen=True)
class PolicyEntry:
    """A policy by name: how to build it ("module:function", imported only when it is built) and what it needs."""

    name: str
    build: str
    summary: str
    task: str | None = None  # the one task it solves (a scripted baseline reading that task's state); None: any
    reads_images: bool = False  # whether the robot must render its cameras for it
    path: str | None = None  # the LeRobot checkpoint a pretrained entry loads (a directory or a Hub repo id)
    own_noise: bool = False  # whether its builder applies --policy.noise_std itself
    options: tuple[str, ...] = ()  # the --policy.options it takes

    def builder(self) -> Builder:
        module, _, function = self.build.partition(":")
        try:
            return getattr(import_module(module), function)
        except ModuleNotFoundError as error:
            if error.name != module.split(".")[0]:
                raise
            raise PolicyError(
                f"--policy.type={self.name} needs the {error.name} distribution, which is not installed: "
                f"pip install {error.name}"
            ) from None


# --policy.path, or --policy.type naming a LeRobot policy type (act, diffusion, smolvla, ...) built fresh.
LEROBOT = PolicyEntry("lerobot", PRETRAINED_BUILD, "a LeRobot PreTrainedPolicy", reads_images=True)

POLICIES: dict[str, PolicyEntry] = {}


def register(entry: PolicyEntry) -> None:
    if entry.name in POLICIES or entry.name == LEROBOT.name:
        raise ValueError(f"policy {entry.name!r} is registered twice")
    POLICIES[entry.name] = entry


for _entry in (
    PolicyEntry(
        DEFAULT_POLICY,
        PRETRAINED_BUILD,
        "the learned default: a pixel policy trained on the simulator's demonstrations (weights ship with it)",
        task="language_table",
        reads_images=True,
        path=_shipped_weights("lerobot_policy_tabletop_pointer"),
    ),
    PolicyEntry(
        "oracle",
        "lerobot_contrast.policies.oracle:build",
        "the scripted push oracle, with privileged block poses",
        task="language_table",
        own_noise=True,
    ),
    PolicyEntry("random", "lerobot_contrast.policies.scripted:build", "uniform random end-effector deltas"),
    PolicyEntry(
        "vln_navigator",
        PRETRAINED_BUILD,
        "the learned VLN default: a pixel navigator trained on the apartment's teacher demonstrations (weights ship)",
        task="vln",
        reads_images=True,
        path=_shipped_weights("lerobot_policy_vln_navigator"),
    ),
    PolicyEntry(
        "route_follower",
        "lerobot_contrast.policies.route_follower:build",
        "the scripted navigator following the shortest route",
        task="vln",
    ),
    PolicyEntry(
        "so101_demonstrator",
        "lerobot_contrast.twin.demonstrator:build",
        "the scripted demonstrator on the virtual SO-101: reads each goal and the twin's true scene ([twin] extra)",
        options=("placement",),
    ),
):
    register(_entry)


# A task's own learned default, where it is not the tabletop's.
TASK_DEFAULTS = {"vln": "vln_navigator", "vln_paper": "vln_navigator"}


def default_policy(task: str | None) -> str:
    return TASK_DEFAULTS.get(task or "", DEFAULT_POLICY)


def policy_entry(args: PolicyArgs, task: str | None = None) -> PolicyEntry:
    """--policy.path is a LeRobot policy; --policy.type a registered policy, else a LeRobot policy type; neither:
    the learned default of `task` (a task name)."""
    if args.path is not None:
        return LEROBOT
    return POLICIES.get(args.type or default_policy(task), LEROBOT)


def make_policy(args: PolicyArgs, robot: Robot, task: Task, rename_map: Mapping[str, str] | None = None) -> Policy:
    """The policy `args` names, built for `robot` and `task`; a one-line PolicyError where it cannot run there."""
    entry = policy_entry(args, task.name)
    if rename_map and entry.build != PRETRAINED_BUILD:
        raise PolicyError(
            f"--rename_map: --policy.type={entry.name} reads the robot's own keys; --rename_map is for a LeRobot "
            "policy (--policy.path or a LeRobot --policy.type)"
        )
    unknown = sorted(set(args.options) - set(entry.options))
    if unknown:
        takes = f"it takes {', '.join(entry.options)}" if entry.options else "it takes none"
        raise PolicyError(f"--policy.options: {entry.name} has no option {', '.join(unknown)}; {takes}")
    noisy = args.noise_std > 0 and not entry.own_noise
    if noisy and entry.build != PRETRAINED_BUILD:
        raise PolicyError(
            f"--policy.noise_std: --policy.type={entry.name} takes no action noise; it applies to the oracle "
            "and to LeRobot policies (the learned default included)"
        )
    if entry.path is not None:
        args = dataclasses.replace(args, path=entry.path)
    policy = entry.builder()(args, robot, task, dict(rename_map or {}))
    return NoisyPolicy(policy, args.noise_std) if noisy else policy


__all__ = [
    "DEFAULT_POLICY",
    "LEROBOT",
    "POLICIES",
    "Policy",
    "PolicyArgs",
    "PolicyEntry",
    "PolicyError",
    "default_policy",
    "make_policy",
    "policy_entry",
    "register",
]
