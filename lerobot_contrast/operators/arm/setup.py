"""Build the arm operator of a run, refusing in one line what it cannot work with."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.operators.arm.args import AUDIT_AT, UNSURE, ArmArgs


def arm_operator(
    args: ArmArgs, robot: Any, task: Any, bench: Any, person: Any, run_dir: Callable[[], Path | None], seed: int
):
    """The arm as operator of `robot` (an SO-101 through LeRobot's so101_follower) on a task file's table, seeing
    through `bench`'s calibrated camera; `person`: the console it calls when it needs a hand; `seed`: the run's, which
    draws the audit."""
    if args.unsure not in UNSURE:
        raise UserError(f"--arm.unsure: unknown {args.unsure!r}; choose from: {', '.join(UNSURE)}")
    if args.tries < 1 or args.pace <= 0 or args.uncertainty < 0:
        raise UserError("--arm.tries must be at least 1, --arm.pace above 0 and --arm.uncertainty at least 0")
    if args.audit_at not in AUDIT_AT:
        raise UserError(f"--arm.audit_at: unknown {args.audit_at!r}; choose from: {', '.join(AUDIT_AT)}")
    if not 0 <= args.audit <= 1:
        raise UserError(f"--arm.audit={args.audit:g}: give the share of trials a person labels too, from 0 to 1")
    if getattr(robot, "robot_type", None) != "so_follower":
        raise UserError(
            f"--operator=arm stages with an SO-101 (--robot.type=so101_follower); {robot.name} is not one, so use "
            "--operator=console"
        )
    if getattr(task, "spec", None) is None:
        raise UserError("--operator=arm needs a task file's table (--task=so101_blocks, so101_red_left or yours)")
    if bench is None or not hasattr(bench, "calibration"):
        raise UserError(
            "--operator=arm needs a calibrated camera to see the table: run python -m lerobot_contrast.calibrate with "
            "your --task and --robot flags, or give --staging.calibration=PATH"
        )
    from lerobot_contrast.so101 import marker

    purple = [name for name, colour in bench.geometry.colours.items() if colour == marker.COLOUR]
    if args.measure_joints and purple:
        raise UserError(
            f"--arm.measure_joints finds the {marker.COLOUR} ball on the arm's jaw, and {purple[0]} has its colour: "
            "take it off the table while the joints are measured, or pass --arm.measure_joints=false"
        )
    from lerobot_contrast.operators.arm.memory import ArmMemory
    from lerobot_contrast.operators.arm.operator import ArmOperator

    return ArmOperator(robot, task, bench, person, args, ArmMemory(run_dir), seed)
