"""The observers (Rerun, dataset) that watch every episode step by step, and what they report back."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from lerobot_contrast.contrast.trial import TrialContext, TrialRecord


@dataclass(frozen=True)
class EpisodeFiles:
    """Where an observer put the episode, merged into the trial's record."""

    rerun_path: str | None = None
    dataset_episode: int | None = None


class EpisodeObserver(Protocol):
    """Watches episodes: `rollback` once when recording into a run directory, then per episode `start`, then
    `step` once per control step, then exactly one of `end` or `discard`.

    `features` are the robot's LeRobot features: {"observation": robot.observation_features,
    "action": robot.action_features}. Observations are the robot's flat dicts (floats, HxWxC uint8 images),
    actions the dicts sent to `send_action`. `pose_keys` names the observation keys holding the robot's
    (or effector's) planar x, y in the scene frame, when it reports them."""

    def rollback(self, records: Sequence[TrialRecord]) -> None:
        """Before the run goes on from its journal's `records`: remove what was written for any later trial (a run
        killed after an episode was saved, before its journal line), so the files match the journal."""
        ...

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None: ...

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None: ...

    def end(self, record: TrialRecord) -> EpisodeFiles:
        """The episode is over: `record` is its scored journal record (cost, metrics, the scene left behind)."""
        ...

    def discard(self) -> None:
        """Drop the episode in progress (the operator chose to redo or skip the trial)."""
        ...

    def close(self) -> None:
        """Finish the session's files (e.g. finalize a dataset); called once, also after an interruption."""
        ...


class QuietObserver:
    """An observer that does nothing: subclass it to watch only what you need (timings, actions)."""

    def rollback(self, records: Sequence[TrialRecord]) -> None:
        pass

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None:
        pass

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None:
        pass

    def end(self, record: TrialRecord) -> EpisodeFiles:
        return EpisodeFiles()

    def discard(self) -> None:
        pass

    def close(self) -> None:
        pass
