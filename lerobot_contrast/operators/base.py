"""What the evaluator asks of whoever stages and labels trials on a robot that cannot do it in software: the
operator interface, and the records it answers with. The person at the console (console.py), the arm with its
camera (arm.py) and programs answering the console's structured channel (channel.py) all speak it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.task import Judgement
from lerobot_contrast.contrast.trial import TrialContext


class SessionStopped(Exception):
    """The operator stopped the session (or their input ended); the run is resumable."""


@dataclass(frozen=True)
class Staging:
    action: str  # "ready" | "skip" | "stop"
    reset_s: float = 0.0
    moved: float | None = None  # the operator's own figure for the distance moved, when it differs from the plan
    measured: Mapping[str, Any] | None = None  # what a calibrated camera measured of the staging (staging/check.py)
    robot_s: float = 0.0  # seconds the robot itself spent staging (an arm operator), beside a person's reset_s
    interventions: int = 0  # times a person was called to the bench while staging


@dataclass(frozen=True)
class Label:
    action: str  # "done" | "redo" | "skip" | "stop"
    success: bool = False
    progress: float | None = None
    unlabelled: bool = False  # recorded without a label, for review later (an arm operator unsure of the outcome)
    asked: bool = False  # a person was called to give this label (an arm operator unsure of the outcome)
    audit: bool | None = None  # a person's own label of an audited trial, beside the camera's (an arm operator)
    audit_drawn: bool = False  # the audit drew this trial: a person labels it, at the bench or later in the viewer


class Operator(Protocol):
    """Stages each trial, checks the staging, labels the outcome and hears of aborts. `bench` is the calibrated
    camera that checks a person's staging, or None."""

    bench: Any

    def stage(self, context: TrialContext) -> Staging:
        """Put the scene of `context.instance` in place (or say to skip the trial or stop)."""

    def fix_or_accept(self, off: Mapping[str, float | None], tolerance: float) -> str:
        """The staging check found `off` (metres past tolerance; None: not seen): "fix", "accept" or "stop"."""

    def running(self) -> None:
        """The policy's episode starts."""

    def take_key(self) -> str | None:
        """An in-trial key pressed since the last call ("success", "failure", "estop"), else None; never blocks."""

    def label(self, subgoals: Sequence[str], suggestion: Judgement | None, early: str | None) -> Label:
        """How the trial went; `suggestion` is what the robot's scene shows, `early` an in-trial key's verdict."""

    def aborted(self, reason: str) -> Label:
        """The trial was aborted (`reason`); "stop" ends the session."""

    def say(self, text: str) -> None:
        """Tell whoever watches the session something (one line, Rich markup allowed)."""

    def scene_after(self, robot: Any, staged: Scene, staging: Staging) -> Scene:
        """Where the episode left the objects (`staged`: as staged, the robot where the episode ended it)."""
