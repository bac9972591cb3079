"""The arm as its own operator, connected to a running twin as to a bench: LeRobot's so101_follower and zmq camera
and the table's calibration, with a console nobody answers. For the benchmarks and tests that drive the arm's parts
(its look, its motions) without a whole evaluation."""

from __future__ import annotations

import io
import shlex
from pathlib import Path
from typing import Any

from lerobot_contrast.twin.launch import RunningTwin

CONNECT_TRIES = 3  # a loaded machine's pty bus may miss a status packet while connecting


def connected_arm(twin: RunningTwin, table: Path, task_name: str, args: Any = None) -> tuple[Any, Any]:
    """(robot, ArmOperator) on `twin`, connected, with `args` (ArmArgs; default: the defaults); the caller
    disconnects the robot."""
    from rich.console import Console

    from lerobot_contrast.clock.robot_clock import use_clock
    from lerobot_contrast.domains import load_task
    from lerobot_contrast.operators.arm.args import ArmArgs
    from lerobot_contrast.operators.arm.memory import ArmMemory
    from lerobot_contrast.operators.arm.operator import ArmOperator
    from lerobot_contrast.operators.console import Answers, OperatorConsole
    from lerobot_contrast.spine.build import make_robot, register_robots
    from lerobot_contrast.spine.config import EvalConfig
    from lerobot_contrast.spine.flags import parse_config
    from lerobot_contrast.staging.setup import make_bench

    register_robots()
    flags = [f"--task={task_name}", *shlex.split(twin.robot_flags), f"--staging.calibration={table}"]
    cfg = parse_config(EvalConfig, [*flags, "--staging.viewer=none"])
    robot = make_robot(cfg)
    clock = use_clock(cfg.clock)  # the twin's, where it was started with --clock=sim
    for attempt in range(CONNECT_TRIES):
        try:
            robot.connect()
            break
        except ConnectionError:
            if attempt == CONNECT_TRIES - 1:
                raise
            robot.bus.disconnect(disable_torque=False)
    clock.watch(robot)
    task = load_task(task_name)
    camera = make_bench(cfg.staging, cfg.task, task, robot, "distance", lambda: None)
    person = OperatorConsole(Answers(io.StringIO("")), Console(file=io.StringIO()))  # nobody at the bench
    return robot, ArmOperator(robot, task, camera, person, args or ArmArgs(), ArmMemory(lambda: None))
