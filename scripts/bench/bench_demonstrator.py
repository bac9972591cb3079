"""The scripted demonstrator's success on every so101_blocks instruction (each template and wording, both bins, every
cube), on the virtual SO-101 through LeRobot's own SO101Follower, judged from the twin's true scene.

    python scripts/bench/bench_demonstrator.py [--seed=0] [--episodes=24] [--pace=1.5]

Prints one line per episode, then `episodes=.. success=.. mean_episode_s=..` last."""

from __future__ import annotations

import argparse
import itertools
import os
import sys
import tempfile
import time
from pathlib import Path

FPS = 30
SETTLE_S = 0.5  # after the motion, for the cube to come to rest before it is judged
CONNECT_TRIES = 5  # on a loaded machine the twin's bus sometimes misses LeRobot's 50 ms reply deadline


def instructions(task) -> list[str]:
    """Every wording of every template with every choice of the objects on the table and of the bins."""
    from lerobot_contrast.domains.task_file.goals import compose

    spec, said = task.spec, []
    for template in spec.templates.values():
        names = list(template.slots)
        options = [
            [c for c in template.slots[n].candidates if c not in spec.objects or c in spec.placed] for n in names
        ]
        for values in itertools.product(*options):
            if len(set(values)) == len(values):
                slots = dict(zip(names, values, strict=True))
                words = {n: spec.words(v)[0] for n, v in slots.items()}
                said += [compose(template, text, slots, words)[0] for text in template.texts]
    return said


def episode(robot, teleop, task) -> tuple[bool, float, int]:
    """Run one demonstration through the follower; whether its goal holds after, the motion's length (s) and the
    reads the bus missed (the demonstrator plays its plan open loop, so a missed read costs nothing but the read)."""
    from lerobot_contrast.contrast.scene import Pose, Scene
    from lerobot_contrast.domains.task_file.goals import holds

    start = time.monotonic()
    teleop.begin_episode(start)
    length, missed = teleop.schedule_s, 0
    while (now := time.monotonic()) - start < length + SETTLE_S:
        try:
            robot.get_observation()
        except ConnectionError:
            missed += 1
        robot.send_action(teleop.get_action())
        time.sleep(max(0.0, 1 / FPS - (time.monotonic() - now)))
    objects = teleop.ask({"cmd": "scene"})["objects"]
    scene = Scene({name: Pose(*pose) for name, pose in objects.items()})
    return holds(teleop.predicate, scene, task.spec.workspace.regions), length, missed


def connect(robot) -> None:
    for attempt in range(CONNECT_TRIES):
        try:
            robot.connect(calibrate=False)
            return
        except (ConnectionError, RuntimeError):
            if attempt == CONNECT_TRIES - 1:
                raise
            if robot.bus.is_connected:  # the port opened before the reply was missed: close it to try again
                robot.bus.disconnect(disable_torque=False)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, help="default: one per instruction; more go round the list again")
    parser.add_argument("--pace", type=float, default=1.5)
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig
    from lerobot_teleoperator_so101_demo import SO101Demo, SO101DemoConfig

    from lerobot_contrast.domains.task_file import load_task_file
    from lerobot_contrast.ports import free_port
    from lerobot_contrast.twin.launch import start_twin

    task = load_task_file("so101_blocks")
    every = instructions(task)
    said = [every[k % len(every)] for k in range(args.episodes or len(every))]
    with tempfile.TemporaryDirectory() as calibration:
        twin = start_twin(f"--calibration_dir={calibration}", f"--camera_port={free_port()}",
                          f"--control_port={free_port()}", "--width=64", "--height=48", "--fps=5")  # fmt: skip
        robot = SO101Follower(SO101FollowerConfig(port=twin.port, id="twin", calibration_dir=Path(calibration)))
        results, lengths, missed, began = [], [], 0, time.monotonic()
        try:
            connect(robot)
            for k, instruction in enumerate(said):
                config = SO101DemoConfig(placement=twin.placement, instruction=instruction, episode_time_s=3600,
                                         seed=args.seed, first_episode=k, pace=args.pace)  # fmt: skip
                teleop = SO101Demo(config)
                teleop.connect()
                ok, length, misses = episode(robot, teleop, task)
                missed += misses
                teleop.disconnect()
                results.append(ok)
                lengths.append(length)
                print(f"{k + 1}/{len(said)} {'ok  ' if ok else 'FAIL'} {instruction} ({length:.1f} s)", flush=True)
        finally:
            if robot.is_connected:
                robot.disconnect()
            twin.stop()
    wall = time.monotonic() - began
    success = sum(results) / len(results)
    print(f"episodes={len(results)} success={success:.3f} mean_episode_s={sum(lengths) / len(lengths):.2f} "
          f"wall_s={wall:.0f} missed_reads={missed}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
