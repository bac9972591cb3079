"""The `--arm.*` flags of `python -m lerobot_contrast.eval --operator=arm` (light: read before anything heavy loads)."""

from __future__ import annotations

from dataclasses import dataclass

UNSURE = ("ask", "unlabelled")
AUDIT_AT = ("live", "viewer")


@dataclass
class ArmArgs:
    """The arm as its own operator (--operator=arm): it stages each trial and labels it with the calibrated camera."""

    # Before the run's first trial, measure each joint's calibration offset with the camera: the jaws move through
    # views of the workspace (about a minute) and the camera finds a 2 cm purple ball fixed on the fixed jaw's outer
    # face (docs/unattended.md). false: trust LeRobot's calibration of the joints as it is.
    measure_joints: bool = True
    # Rounds of pick-and-place the arm tries before it calls a person to place what is still off target.
    tries: int = 3
    # Each motion's time as a multiple of the planner's (larger: slower and surer).
    pace: float = 1.5
    # Metres the camera may be off in what a goal tests (a cube's distance from another, or from a bin's centre): a
    # label that turns when a named object is moved up to this far is unsure. Measure your bench (docs/unattended.md);
    # the default covers the twin's camera, measured by scripts/bench/bench_seeing.py at 0.21 cm (p95).
    uncertainty: float = 0.003
    # What an unsure label does: ask (a person at the console labels it) or unlabelled (recorded for review later).
    unsure: str = "ask"
    # The share of trials a person labels too, drawn at random from the run's seed whatever the camera's confidence:
    # the audit that the report's prediction-powered estimates correct the camera's labels with (0: none).
    audit: float = 0.0
    # When the person labels an audited trial: live (at the bench, as the trial ends; a session killed while it asks
    # runs the trial again) or viewer (later, from the episode's video on the run viewer's audit page, beside a session
    # still running; the camera's label is journalled at once, the person's kept in audit.jsonl).
    audit_at: str = "live"
