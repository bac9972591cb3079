"""Benchmark LIBERO through LeRobot's LiberoEnv behind `libero_sim`: control steps per second with both cameras at
128x128 and at LeRobot's default 360x360, LeRobot's own (hard) reset, and our per-trial overhead (staging a
perturbed scene, settling, reading it back and judging the goal). Figures on the last line."""

from __future__ import annotations

import argparse
import time

import numpy as np

from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.domains.libero.config_libero_sim import LiberoSimConfig
from lerobot_contrast.domains.libero.libero_sim import ACTION, LiberoSim
from lerobot_contrast.domains.libero.task import LiberoObjectTask


def steps_per_s(robot: LiberoSim, steps: int) -> float:
    action = dict.fromkeys(ACTION, 0.0)
    start = time.perf_counter()
    for _ in range(steps):
        robot.send_action(action)
        robot.get_observation()
    return steps / (time.perf_counter() - start)


def trial_overhead_ms(robot: LiberoSim, task: LiberoObjectTask, trials: int) -> float:
    rng = np.random.default_rng(0)
    current = task.sample(1, rng)[0]
    robot.stage_scene(current.scene)
    current = current.derive(scene=robot.read_scene())
    start, n = time.perf_counter(), 0
    for k in range(trials):
        perturbed = perturb(task, task.perturbations.get("S" if k % 2 else "SB"), current, rng)
        if perturbed is None:
            continue
        robot.stage_scene(perturbed.scene)
        current = perturbed.derive(scene=robot.read_scene())
        task.is_achieved(current, current.scene)
        n += 1
    return 1000.0 * (time.perf_counter() - start) / max(n, 1)


def reset_s(robot: LiberoSim, resets: int) -> float:
    """LeRobot's hard reset, what `lerobot-eval` pays per episode (staging builds its worlds with soft resets)."""
    env = robot._require().env
    env._env.env.hard_reset = True
    start = time.perf_counter()
    for _ in range(resets):
        env.reset()
    return (time.perf_counter() - start) / resets


def measure(size: int | None, task: LiberoObjectTask, steps: int) -> tuple[LiberoSim, float]:
    config = LiberoSimConfig() if size is None else LiberoSimConfig(observation_width=size, observation_height=size)
    robot = LiberoSim(config)
    robot.connect()
    robot.stage_scene(task.sample(1, np.random.default_rng(0))[0].scene)
    return robot, steps_per_s(robot, steps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--trials", type=int, default=6)
    parser.add_argument("--resets", type=int, default=2)
    args = parser.parse_args()
    task = LiberoObjectTask(families=["task0"])
    small, fast = measure(128, task, args.steps)
    overhead = trial_overhead_ms(small, task, args.trials)
    reset = reset_s(small, args.resets)
    small.disconnect()
    default, slow = measure(None, task, args.steps)
    default.disconnect()
    print(
        f"libero_object task 0, both cameras; {args.steps} steps, {args.trials} staged perturbations, {args.resets} resets"
    )
    print(
        f"steps_per_s_128={fast:.2f} steps_per_s_default={slow:.2f} reset_s={reset:.2f} trial_overhead_ms={overhead:.0f}"
    )


if __name__ == "__main__":
    main()
