"""The LoCoBot's LeRobot action modes: VLN-CE discrete steps (named in the shared `navigation_protocol`) or
base velocities as float actions."""

from __future__ import annotations

from navigation_protocol import DISCRETE_KEYS

VELOCITY_KEYS = ("x.vel", "theta.vel")
ACTION_MODES = ("discrete", "velocity")


def action_features(mode: str) -> dict[str, type]:
    keys = DISCRETE_KEYS if mode == "discrete" else VELOCITY_KEYS
    return dict.fromkeys(keys, float)


def clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, float(value)))
