"""Time LeRobot's own `SO101Follower` on the virtual SO-101's serial bus, from a process that loads no code of this
project (the twin's bus runs in a child process); with --eval, then the evaluator on the whole twin (640x480 camera,
30 Hz, the scripted operator, a random-weight ACT sized as the CPU recipe trains one, at 160x120): the control
loop's mean period, how often the staging camera flags cubes placed 4 cm and 0.5 cm off, and --cost=measured against
the twin's truth.

Figures last: connect_s=... connect_failures=... (before the first connect that worked) reach_s=... (the slowest of the poses to within 2 degrees) sync_read_ms=...
sync_write_ms=... write_ms=... lost_calls=... project_code_loaded=false [flagged_4cm=... measured_cost_err_cm_4cm=...
measured_cube_err_cm_4cm=... (and the same for 0.5 cm) period_ms=...] clock=wall. It times LeRobot's deadlines and
the control loop in real time, so the twin runs on the wall clock, never its simulated one.

    .venv/bin/python scripts/bench/bench_twin.py [--eval --instances=4]
"""

from __future__ import annotations

import argparse
import itertools
import math
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
    from lerobot_contrast.so101 import arm
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


LOST: list[int] = [0]  # calls that failed after their retries: LeRobot's reply deadline missed three times


def mean_ms(call, repeats: int) -> float:
    """Mean milliseconds per call; each retries twice, as `so101_follower` retries its reads (a busy machine can
    make the twin miss LeRobot's 50 ms reply deadline now and then); calls that fail even so are counted in LOST."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        try:
            call()
        except ConnectionError:
            LOST[0] += 1
        times.append(time.perf_counter() - start)
    return statistics.fmean(times) * 1e3


def confirmed_sync_write(bus, values: dict[str, int]) -> None:
    """Write Goal_Position to every motor, then read it back until the servos hold it: the write's round trip."""
    bus.sync_write("Goal_Position", values, normalize=False)
    while bus.sync_read("Goal_Position", normalize=False, num_retry=2) != values:
        pass


def measure(port: str, calibration_dir: Path, robot_id: str, repeats: int) -> dict[str, str]:
    failures = 0  # LeRobot does not retry a connect; a loaded machine can make the twin miss a reply
    while True:
        robot = SO101Follower(SO101FollowerConfig(port=port, id=robot_id, calibration_dir=calibration_dir))
        start = time.perf_counter()
        try:
            robot.connect()
            break
        except (ConnectionError, RuntimeError):
            robot.bus.port_handler.closePort()
            failures += 1
            if failures == 5:
                sys.exit("bench_twin: 5 connects in a row failed")
    connect_s = time.perf_counter() - start
    reach_s = max(reach_seconds(robot, pose) for pose in POSES)
    bus = robot.bus
    here = bus.sync_read("Present_Position", normalize=False)
    there = {name: value + 1 for name, value in here.items()}
    goals = itertools.cycle([there, here])  # two goals one step apart, so each write changes the registers
    figures = {
        "connect_s": f"{connect_s:.3f}",
        "connect_failures": str(failures),
        "reach_s": f"{reach_s:.3f}",
        "sync_read_ms": f"{mean_ms(lambda: bus.sync_read('Present_Position', num_retry=2), repeats):.3f}",
        "sync_write_ms": f"{mean_ms(lambda: confirmed_sync_write(bus, next(goals)), repeats):.3f}",
        "write_ms": f"{mean_ms(lambda: bus.write('Goal_Position', 'gripper', here['gripper'], normalize=False, num_retry=2), repeats):.3f}",
    }
    figures["lost_calls"] = str(LOST[0])
    robot.disconnect()
    return figures


def eval_figures(work: Path, instances: int) -> dict[str, str]:
    """The evaluator on the whole twin; the bench's own process loads the project from here on."""
    import json
    import os
    import re
    import shlex
    import subprocess

    from lerobot_contrast.ports import free_port

    camera, control = free_port(), free_port()
    python = sys.executable
    twin = subprocess.Popen(
        [python, "-m", "lerobot_contrast.twin", f"--calibration_dir={work / 'calibration'}",
         f"--camera_port={camera}", f"--control_port={control}"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        flags = next(shlex.split(line[12:]) for line in twin.stdout if line.startswith("eval flags: "))
        policy = save_act(work / "act")
        from lerobot_contrast.domains.task_file import load_task_file
        from lerobot_contrast.so101.scene import start_poses
        from lerobot_contrast.twin.placement_client import PlacementClient

        placement = PlacementClient(f"tcp://127.0.0.1:{control}")

        for name, pose in start_poses(load_task_file("so101_blocks").spec, None).items():  # clear the board's place
            placement.ask({"cmd": "place", "object": name, "x": pose.x, "y": pose.y})
        placement.ask({"cmd": "board", "x": 0.30, "y": 0.0, "yaw_deg": 0})
        table = work / "table.calibration.json"
        calibrate = [python, "-m", "lerobot_contrast.calibrate", "--task=so101_blocks", "--board.x=0.30",
                     "--board.y=0", "--board.yaw_deg=0", f"--output={table}", *flags]  # fmt: skip
        subprocess.run(calibrate, check=True)
        placement.ask({"cmd": "remove_board"})
        figures, periods = {}, []
        for name, error in (("flagged_4cm", "offset:0.04"), ("flagged_05cm", "offset:0.005")):
            run_dir = work / name
            command = [python, "-m", "lerobot_contrast.twin.operator", f"--placement={placement.address}",
                       f"--placement_error={error}", "--task=so101_blocks", *flags, f"--policy.path={policy}",
                       "--policy.device=cpu", "--strategy=standard", f"--n_instances={instances}", "--fps=30",
                       "--max_episode_s=3", "--cost=measured", f"--staging.calibration={table}",
                       "--staging.viewer=none", f"--output_dir={run_dir}"]  # fmt: skip
            said = subprocess.run(command, capture_output=True, text=True, env={**os.environ}).stdout
            if not (run_dir / "journal.jsonl").is_file():
                sys.exit(f"bench_twin: the evaluation on the twin did not run: {said.strip().splitlines()[-1:]}")
            records = [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]
            placed, flagged = 0, 0
            for record, trial in zip(records, re.split(r"trial \d+/\d+ · ", said)[1:], strict=False):
                off = record["extra"]["staging"]["off_m"]
                for cube in re.findall(r"\[operator\] placed (\w+) ", trial):
                    placed, flagged = placed + 1, flagged + (off.get(cube) is None or off[cube] > 0)
            figures[name] = f"{flagged / max(placed, 1):.3f}"
            periods += [r["duration_s"] / r["steps"] for r in records if r["status"] == "done" and r["steps"]]
            truth = [float(x) for x in re.findall(r"\[operator\] moved (\d+\.\d+) m", said)]
            errors = [abs(r["extra"]["staging"]["moved_m"] - t) for r, t in zip(records, truth, strict=False)]
            figures[f"measured_cost_err_cm_{name[8:]}"] = f"{max(errors, default=float('nan')) * 100:.2f}"
            cubes = re.findall(r"\[operator\] moved [\d.]+ m \(the twin's truth: ([^)]*)\)", said)
            each = [cube_errors(r["extra"]["staging"], t) for r, t in zip(records, cubes, strict=False)]
            figures[f"measured_cube_err_cm_{name[8:]}"] = f"{max(sum(each, []), default=float('nan')) * 100:.2f}"
        figures["period_ms"] = f"{statistics.fmean(periods) * 1e3:.1f}"
        return figures
    finally:
        twin.terminate()
        twin.wait(timeout=30)


def cube_errors(staging: dict, truth: str) -> list[float]:
    """Per object the twin says moved: how far the camera's measured move is from it (m)."""
    errors = []
    for item in filter(None, truth.split(", ")):
        name, distance = item.rsplit(" ", 1)
        if name in staging["placed"] and name in staging["before"]:
            (x0, y0, *_), (x1, y1) = staging["before"][name], staging["placed"][name]
            errors.append(abs(math.hypot(x1 - x0, y1 - y0) - float(distance)))
    return errors


def save_act(directory: Path) -> Path:
    """A random-weight ACT shaped as scripts/train/train_so101_act.py trains one for this CPU (frames of 160x120, its
    transformer and chunks): the camera's 640x480 frames reach it scaled, as they would a policy recorded at 160x120."""
    from lerobot.cameras.zmq import ZMQCameraConfig

    from lerobot_contrast.policies.pretrained import save_fresh_policy
    from lerobot_contrast.training.act_recipe import ARCHITECTURE

    camera = ZMQCameraConfig(server_address="127.0.0.1", port=5555, camera_name="front", width=160, height=120, fps=30)
    config = SO101FollowerConfig(port="unused", id="act", calibration_dir=directory / "calibration",
                                 cameras={"front": camera})  # fmt: skip
    return save_fresh_policy(SO101Follower(config), "act", directory, device="cpu", **ARCHITECTURE)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=300, help="calls per latency figure")
    parser.add_argument("--eval", action="store_true", help="then time the evaluator on the whole twin")
    parser.add_argument("--instances", type=int, default=4, help="trials per staging figure (--eval)")
    parser.add_argument(
        "--work", type=Path, default=None, help="keep the --eval runs here (default: a temporary folder)"
    )
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
    if args.eval and args.work is not None:
        figures |= eval_figures(args.work, args.instances)
    elif args.eval:
        with tempfile.TemporaryDirectory() as work:
            figures |= eval_figures(Path(work), args.instances)
    figures["clock"] = "wall"
    print(" ".join(f"{name}={value}" for name, value in figures.items()))


if __name__ == "__main__":
    main()
