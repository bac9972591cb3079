"""What runners share: the context of one trial, the robots that can read and stage their scene, and the
observers (Rerun, dataset) that watch every episode step by step."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.trial import Outcome


@dataclass(frozen=True)
class TrialContext:
    """Everything a runner and its observers know about a trial before it runs."""

    index: int
    instance: Instance
    base: Instance  # the i.i.d. instance this trial derives from (the instance itself for an original)
    current: Scene  # the scene the robot left behind; the operator stages `instance.scene` from it
    planned_cost: float
    staging: str  # "reset" | "in_place"
    rng: np.random.Generator
    planned_trials: int
    axis: str | None = None  # L | LB | S | SB, None for an original
    settings: dict[str, Any] = field(default_factory=dict)  # strategy, policy, task: for recording properties


@runtime_checkable
class SceneIO(Protocol):
    """A robot (simulated, or with a perception stack) that can report and set its scene.

    The runner then stages scenes and judges predicates without asking the operator."""

    def read_scene(self) -> Scene: ...

    def stage_scene(self, scene: Scene) -> None: ...


def reports_scene(robot: Any, objects: Iterable[str] = ()) -> bool:
    """Whether `robot` can read and stage a scene of `objects` now.

    A remote host may report that it cannot (`supports_scene_io`); a simulator places only the objects
    it models (`stageable_objects`)."""
    if not (isinstance(robot, SceneIO) and getattr(robot, "supports_scene_io", True)):
        return False
    stageable = getattr(robot, "stageable_objects", None)
    return stageable is None or set(objects) <= set(stageable)


@dataclass(frozen=True)
class EpisodeFiles:
    """Where an observer put the episode, merged into the trial's record."""

    rerun_path: str | None = None
    dataset_episode: int | None = None


class EpisodeObserver(Protocol):
    """Watches episodes: `start`, then `step` once per control step, then exactly one of `end` or `discard`.

    `features` are the robot's LeRobot features: {"observation": robot.observation_features,
    "action": robot.action_features}. Observations are the robot's flat dicts (floats, HxWxC uint8 images),
    actions the dicts sent to `send_action`. `pose_keys` names the observation keys holding the robot's
    (or effector's) planar x, y in the scene frame, when it reports them."""

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None: ...

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None: ...

    def end(self, outcome: Outcome, cost: float) -> EpisodeFiles: ...

    def discard(self) -> None:
        """Drop the episode in progress (the operator chose to redo or skip the trial)."""
        ...

    def close(self) -> None:
        """Finish the session's files (e.g. finalize a dataset); called once, also after an interruption."""
        ...


class QuietObserver:
    """An observer that does nothing: subclass it to watch only what you need (timings, actions)."""

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None:
        pass

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None:
        pass

    def end(self, outcome: Outcome, cost: float) -> EpisodeFiles:
        return EpisodeFiles()

    def discard(self) -> None:
        pass

    def close(self) -> None:
        pass
