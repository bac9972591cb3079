"""The parsed task file: frozen records for the workspace, objects, templates, instances, outcome,
perturbations and cost. All lengths are in metres and angles in radians, whatever units the file uses."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from lerobot_contrast.contrast.scene import Pose

VERSION = 1
ROBOT = "robot"  # the subject name for goals about the robot's own pose


@dataclass(frozen=True)
class Region:
    """A named area of the workspace: a disc (`center`, `radius`) or an axis-aligned box (`x`, `y`)."""

    name: str
    words: tuple[str, ...]
    center: tuple[float, float] | None = None
    radius: float | None = None
    x: tuple[float, float] | None = None
    y: tuple[float, float] | None = None

    def contains(self, x: float, y: float) -> bool:
        if self.center is not None:
            return math.hypot(x - self.center[0], y - self.center[1]) <= self.radius
        return self.x[0] <= x <= self.x[1] and self.y[0] <= y <= self.y[1]

    @property
    def middle(self) -> tuple[float, float]:
        if self.center is not None:
            return self.center
        return (sum(self.x) / 2, sum(self.y) / 2)

    @property
    def box(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The bounding box ((x_min, x_max), (y_min, y_max))."""
        if self.center is not None:
            (cx, cy), r = self.center, self.radius
            return (cx - r, cx + r), (cy - r, cy + r)
        return self.x, self.y


@dataclass(frozen=True)
class Workspace:
    units: str
    area: Region  # the bounds, as a box region named "workspace"
    min_spacing: float
    regions: Mapping[str, Region]
    robot_start: Pose | None = None
    storage: tuple[tuple[float, float], tuple[float, float]] | None = None
    tray: Region | None = None  # inside the bounds, apart from every area: where spare objects wait in view and reach


@dataclass(frozen=True)
class ObjectSpec:
    name: str
    attributes: Mapping[str, str]
    words: tuple[str, ...]
    movable: bool = True
    spare: bool = False  # movable but not placed in the evaluation set's scenes: a distractor to add
    at: Pose | None = None  # where a fixed object is
    area: str | None = None  # the region a movable object is placed in (None: anywhere in the workspace)


@dataclass(frozen=True)
class Slot:
    name: str
    kind: str  # "object" | "region"
    candidates: tuple[str, ...]


@dataclass(frozen=True)
class Predicate:
    """Success on object poses: `subject` inside region `region`, or within `within` of object `near`.

    Names may be slot references "{slot}" in a template; in an instance's goal they are resolved."""

    subject: str
    region: str | None = None
    near: str | None = None
    within: float | None = None


@dataclass(frozen=True)
class Template:
    key: str  # unique: the template's name, or "instances[k]" for a listed instruction without a template
    family: str
    texts: tuple[str, ...]  # alternative wordings with the same slots; the first is used for originals
    slots: Mapping[str, Slot]
    goal: Predicate | None
    subgoals: tuple[str, ...] = ()
    reference: float | str | None = None  # metres, "straight_line", or None (no SPL)
    weight: float = 1.0

    def takes(self, values: Mapping[str, str]) -> bool:
        """Whether every slot named in `values` is one of this template's and may hold its value."""
        return all(name in self.slots and value in self.slots[name].candidates for name, value in values.items())


@dataclass(frozen=True)
class ListedInstance:
    template: Template
    slots: Mapping[str, str]
    placements: Mapping[str, Pose]
    robot: Pose | None


@dataclass(frozen=True)
class PerturbationSpec:
    name: str
    axis: str
    kind: str  # a generic kind, or "custom"
    params: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""
    function: Callable[..., Any] | None = None


@dataclass(frozen=True)
class CostSpec:
    tolerance: float = 0.005
    add_remove: float = 0.0  # metres charged by the distance model for bringing an object in or out
    hand_speed: float = 0.25  # metres per second, for the reset-time model
    default_handling_s: float = 3.0
    handling_s: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class TaskSpec:
    name: str
    source: str
    description: str
    workspace: Workspace
    objects: Mapping[str, ObjectSpec]
    templates: Mapping[str, Template]
    instances: tuple[ListedInstance, ...] | None  # None: sample from the templates
    seed: int | None
    outcome: str
    perturbations: tuple[PerturbationSpec, ...]
    cost: CostSpec
    base_slots: Mapping[str, str] = field(default_factory=dict)  # sampler.slots: what every sampled base says

    def fits_bases(self, template: Template) -> bool:
        """Whether `template` can give a base with every slot `sampler.slots` fixes."""
        return template.takes(self.base_slots)

    def words(self, name: str) -> tuple[str, ...]:
        """How the instructions may refer to an object or region; the first is the plain one."""
        if name in self.objects:
            return self.objects[name].words
        return self.workspace.regions[name].words

    @property
    def placed(self) -> tuple[str, ...]:
        """Movable objects that every scene of the evaluation set contains."""
        return tuple(n for n, o in self.objects.items() if o.movable and not o.spare)
