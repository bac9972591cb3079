"""What a navigating robot and the evaluator agree on, and all they share: VLN-CE's discrete actions as LeRobot
features, the odometry state, and the camera names. Both the LoCoBot plugin and the evaluator's in-process
simulated apartment import this; neither imports the other. Pure Python, no dependencies.

LeRobot keeps only float scalars whose keys end in `.vel`/`.pos` as robot state and action (lerobot-rollout),
so the four discrete actions are one float each (`forward.vel`, ...): the largest positive one is executed.
Odometry is `odom.x`/`odom.y`/`odom.theta`, not `*.pos`, so no tool tries to drive the base "back" to it."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

COMMANDS = ("forward", "turn_left", "turn_right", "stop")
DISCRETE_KEYS = tuple(f"{command}.vel" for command in COMMANDS)
STATE_KEYS = ("odom.x", "odom.y", "odom.theta", "x.vel", "theta.vel", "bumper")
# The observation keys holding the base's planar position in the scene frame.
POSE_KEYS = ("odom.x", "odom.y")
CAMERA = "front"
DEPTH = "front_depth"


def discrete_command(action: Mapping[str, Any]) -> str | None:
    """The command whose key holds the largest positive value (one-hot or scores); None if none is positive."""
    unknown = set(action) - set(DISCRETE_KEYS)
    if unknown:
        raise ValueError(f"unknown discrete action keys {sorted(unknown)}; expected {list(DISCRETE_KEYS)}")
    values = [float(action.get(key, 0.0)) for key in DISCRETE_KEYS]
    best = max(range(len(values)), key=values.__getitem__)
    return COMMANDS[best] if values[best] > 0.0 else None


def one_hot(command: str | None) -> dict[str, float]:
    """The discrete action dict for `command` (all zeros for None: no action)."""
    if command is not None and command not in COMMANDS:
        raise ValueError(f"unknown navigation command {command!r}; choose from {list(COMMANDS)}")
    return {f"{c}.vel": float(c == command) for c in COMMANDS}


def is_stop(action: Mapping[str, Any]) -> bool:
    """Whether a discrete action asks the robot to stop (the end of a VLN episode)."""
    return all(key in DISCRETE_KEYS for key in action) and discrete_command(action) == "stop"
