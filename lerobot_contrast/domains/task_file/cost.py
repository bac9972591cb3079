"""A task file's cost models: distance moved (with its tolerance and add/remove charge) and reset time with a
handling time per object, built from the core's cost models."""

from __future__ import annotations

from lerobot_contrast.contrast.cost import (
    COST_MODELS,
    CostModel,
    DistanceCost,
    InterventionCost,
    ResetTimeCost,
    RobotTimeCost,
)
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.task_file.schema import CostSpec


def make_cost_model(spec: CostSpec, name: str) -> CostModel:
    """The `--cost` model `name` with the task file's parameters."""
    if name in ("distance", "measured"):  # measured: planned as distance, then measured by a calibrated camera
        return DistanceCost(tolerance=spec.tolerance, add_remove_m=spec.add_remove, name=name)
    if name == "reset_time":
        return ResetTimeCost(
            per_object_s=spec.default_handling_s,
            hand_speed_m_s=spec.hand_speed,
            tolerance=spec.tolerance,
            handling_s=dict(spec.handling_s),
        )
    if name == "robot_time":  # the seconds per object come from the arm that stages (spine/run_setup.py)
        return RobotTimeCost(tolerance=spec.tolerance)
    if name == "interventions":
        return InterventionCost()
    raise UserError(f"--cost: unknown cost model {name!r}; choose from: {', '.join(COST_MODELS)}")
