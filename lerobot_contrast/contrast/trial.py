"""Trial records: one execution (or skipped perturbation) of one planned trial, as the journal stores it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields
from typing import Any, Literal

import numpy as np

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene

Status = Literal["done", "not_applicable", "aborted", "skipped"]


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
    repeat: int = 0  # which run of the planned trial this is


@dataclass(frozen=True)
class Outcome:
    """What a runner reports after executing an instance.

    `status` is "aborted" after an emergency stop or a lost robot, "skipped" when the operator skipped
    the trial. `cost`, when set, replaces the planned staging cost with what was measured (reset seconds)
    or what the operator reported moving."""

    success: bool
    steps: int
    path_length: float
    scene_after: Scene
    duration_s: float
    progress: float | None = None
    reference_length: float | None = None
    status: Status = "done"
    cost: float | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class TrialRecord:
    """One line of the journal. `instance` is None only for a perturbation that did not apply."""

    index: int
    base_id: str
    perturbation: str | None
    axis: str | None
    family: str
    staging: str
    repeat: int
    status: Status
    instance: Instance | None
    cost: float
    cumulative_cost: float
    success: bool | None = None
    spl: float | None = None
    progress: float | None = None
    path_length: float | None = None
    reference_length: float | None = None
    steps: int | None = None
    duration_s: float | None = None
    started_at: str | None = None
    scene_after: Scene | None = None
    rerun_path: str | None = None
    dataset_episode: int | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def instance_id(self) -> str | None:
        return None if self.instance is None else self.instance.id

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["instance"] = None if self.instance is None else self.instance.to_json()
        data["scene_after"] = None if self.scene_after is None else self.scene_after.to_json()
        data["extra"] = dict(self.extra)
        return data

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TrialRecord:
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in data.items() if k in known}
        if values.get("instance") is not None:
            values["instance"] = Instance.from_json(values["instance"])
        if values.get("scene_after") is not None:
            values["scene_after"] = Scene.from_json(values["scene_after"])
        return cls(**values)
