"""Calibrate the twin's table camera as a person does once per bench: clear the table, lay the printed board,
run `python -m lerobot_contrast.calibrate` through the robot's own flags, take the board away and put the objects
back where they were."""

from __future__ import annotations

import shlex
import subprocess
import sys
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.so101.scene import start_poses
from lerobot_contrast.twin.launch import RunningTwin
from lerobot_contrast.twin.placement_client import PlacementClient

BOARD = {"x": 0.30, "y": 0.0, "yaw_deg": 0.0}  # over the workspace's middle, where the board covers most of it
CONNECT_TRIES = 3


def calibrate_table(twin: RunningTwin, task: str, output: Path) -> Path:
    """Write the table calibration of `twin`'s camera to `output`; one line if it fails."""
    placement = PlacementClient(twin.placement)
    before = placement.poses()
    for name, pose in start_poses(load_task_file(task).spec, None).items():  # off the board's place
        placement.place(name, pose.x, pose.y)
    placement.ask({"cmd": "board", **BOARD})
    board = [f"--board.{key}={value}" for key, value in BOARD.items()]
    command = [sys.executable, "-m", "lerobot_contrast.calibrate", f"--task={task}", *board, f"--output={output}",
               *shlex.split(twin.robot_flags)]  # fmt: skip
    for _ in range(CONNECT_TRIES):  # a loaded machine's pty bus may miss the first status packet of a connect
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode == 0 or "cannot connect" not in done.stderr:
            break
    placement.ask({"cmd": "remove_board"})
    for name, (x, y, _, yaw) in before.items():
        placement.place(name, x, y, yaw)
    if done.returncode != 0:
        said = done.stderr.strip().splitlines()
        raise UserError(f"calibrating the twin's camera failed: {said[-1] if said else 'no output'}")
    return output
