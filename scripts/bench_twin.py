"""Time LeRobot's own `SO101Follower` on the virtual SO-101's serial bus, from a process that loads no code of this
project (the twin's bus runs in a child process). Figures last: connect_s=... reach_s=... (the slowest of the poses
to within 2 degrees) sync_read_ms=... sync_write_ms=... write_ms=... project_code_loaded=false.

    .venv/bin/python scripts/bench_twin.py
"""

from __future__ import annotations

import argparse
import itertools
import multiprocessing
import statistics
import sys
import tempfile
import time
from pathlib import Path

from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig

# Poses within the SO-101 model's joint limits (degrees; the gripper 0-100), each far from the one before.
POSES = [
    {"shoulder_pan": 30, "shoulder_lift": -40, "elbow_flex": 45, "wrist_flex": 30, "wrist_roll": 45, "gripper": 60},
    {"shoulder_pan": -45, "shoulder_lift": 20, "elbow_flex": -30, "wrist_flex": -20, "wrist_roll": -60, "gripper": 10},
    {"shoulder_pan": 0, "shoulder_lift": -90, "elbow_flex": 85, "wrist_flex": 20, "wrist_roll": 0, "gripper": 30},
]


def serve_bus(calibration_dir: str, robot_id: str, ports: multiprocessing.Queue, stop: multiprocessing.Event) -> None:
    """The child: the twin's arm on its bus alone (servos clocked by the wall clock, no physics)."""
    from lerobot_contrast.twin import arm
    from lerobot_contrast.twin.bus_server import BusServer
    from lerobot_contrast.twin.calibration_file import write_calibration_file
    from lerobot_contrast.twin.servos import ServoBank

    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    write_calibration_file(bank, robot_id, calibration_dir)
    with BusServer(bank, clocked=True) as port:
        ports.put(port)
        stop.wait()


def reach_seconds(robot: SO101Follower, pose: dict[str, float], timeout: float = 5.0) -> float:
    goal = {f"{name}.pos": float(value) for name, value in pose.items()}
    start = time.perf_counter()
    robot.send_action(goal)
    while time.perf_counter() - start < timeout:
        obs = robot.get_observation()
        if all(abs(obs[key] - value) <= 2.0 for key, value in goal.items()):
            return time.perf_counter() - start
    sys.exit(f"bench_twin: pose {pose} not reached within {timeout} s (last reading {obs})")


def mean_ms(call, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.fmean(times) * 1e3


def confirmed_sync_write(bus, values: dict[str, int]) -> None:
    """Write Goal_Position to every motor, then read it back until the servos hold it: the write's round trip."""
    bus.sync_write("Goal_Position", values, normalize=False)
    while bus.sync_read("Goal_Position", normalize=False) != values:
        pass


def measure(port: str, calibration_dir: Path, robot_id: str, repeats: int) -> dict[str, str]:
    robot = SO101Follower(SO101FollowerConfig(port=port, id=robot_id, calibration_dir=calibration_dir))
    start = time.perf_counter()
    robot.connect()
    connect_s = time.perf_counter() - start
    reach_s = max(reach_seconds(robot, pose) for pose in POSES)
    bus = robot.bus
    here = bus.sync_read("Present_Position", normalize=False)
    there = {name: value + 1 for name, value in here.items()}
    goals = itertools.cycle([there, here])  # two goals one step apart, so each write changes the registers
    figures = {
        "connect_s": f"{connect_s:.3f}",
        "reach_s": f"{reach_s:.3f}",
        "sync_read_ms": f"{mean_ms(lambda: bus.sync_read('Present_Position'), repeats):.3f}",
        "sync_write_ms": f"{mean_ms(lambda: confirmed_sync_write(bus, next(goals)), repeats):.3f}",
        "write_ms": f"{mean_ms(lambda: bus.write('Goal_Position', 'gripper', here['gripper'], normalize=False), repeats):.3f}",
    }
    robot.disconnect()
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=300, help="calls per latency figure")
    args = parser.parse_args()
    spawn = multiprocessing.get_context("spawn")
    ports, stop = spawn.Queue(), spawn.Event()
    with tempfile.TemporaryDirectory() as calibration_dir:
        child = spawn.Process(target=serve_bus, args=(calibration_dir, "twin", ports, stop), daemon=True)
        child.start()
        try:
            figures = measure(ports.get(timeout=120), Path(calibration_dir), "twin", args.repeats)
        finally:
            stop.set()
            child.join(timeout=10)
    figures["project_code_loaded"] = str(any(m.startswith("lerobot_contrast") for m in sys.modules)).lower()
    print(" ".join(f"{name}={value}" for name, value in figures.items()))


if __name__ == "__main__":
    main()
