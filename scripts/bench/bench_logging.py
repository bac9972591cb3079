"""What recording costs the control loop: a 10 Hz Language-Table loop run bare, with Rerun logging and with
LeRobotDataset recording, on one CPU core (the observers' worker threads share it with the loop).

A step's busy time is everything the loop thread does in one control period (read the observation, act, log,
step the simulator) before it sleeps until the next tick. Overhead per step = busy time with the observer minus
busy time of the bare loop, in ms and as a fraction of the 100 ms control period. Episodes of the three variants
are interleaved so machine load affects them alike. `start()` and `end()` (opening the dataset, writing the
episode) are reported separately: they run between episodes, when the robot is idle.
Usage: python scripts/bench/bench_logging.py [--episodes 4] [--steps 40]. The last line is machine-readable.
"""

from __future__ import annotations

import os

# One core, one BLAS thread: the figure should not depend on how many cores the machine has.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
CPU = min(os.sched_getaffinity(0))
os.sched_setaffinity(0, {CPU})

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from lerobot_contrast.contrast.metrics import scored  # noqa: E402
from lerobot_contrast.contrast.trial import Outcome, TrialContext  # noqa: E402
from lerobot_contrast.domains.language_table import LanguageTableTask  # noqa: E402
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig  # noqa: E402
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim, episode_features  # noqa: E402
from lerobot_contrast.policies.oracle import OraclePolicy  # noqa: E402
from lerobot_contrast.record.dataset import DatasetRecorder  # noqa: E402
from lerobot_contrast.record.observer import QuietObserver  # noqa: E402
from lerobot_contrast.record.rerun_log import RerunEpisodeRecorder  # noqa: E402

PERIOD_S = 0.1  # Language-Table's 10 Hz control
FEATURES = episode_features()
POSE_KEYS = LanguageTableSim.pose_keys


@dataclass
class Timings:
    name: str
    busy_s: list[float] = field(default_factory=list)
    observer_s: list[float] = field(default_factory=list)
    start_end_s: list[float] = field(default_factory=list)
    late: int = 0

    def busy_ms(self) -> float:
        return 1000 * float(np.mean(self.busy_s))


def context(index: int, instance: Any) -> TrialContext:
    return TrialContext(
        index=index,
        instance=instance,
        base=instance,
        current=instance.scene,
        planned_cost=0.0,
        staging="reset",
        rng=np.random.default_rng(index),
        planned_trials=0,
        settings={"task": "language_table", "strategy": "standard", "policy": "oracle", "cost_unit": "m"},
    )


def run_episode(
    robot: LanguageTableSim, task: Any, trial: TrialContext, observer: Any, steps: int, timings: Timings
) -> None:
    """One paced episode: every step starts on its 10 Hz tick; only the loop thread's work is timed."""
    robot.stage_scene(trial.instance.scene)
    policy = OraclePolicy(robot.read_scene, task)
    policy.reset(trial)
    start = time.perf_counter()
    observer.start(trial, FEATURES, POSE_KEYS)
    between = time.perf_counter() - start
    tick = time.perf_counter()
    for k in range(steps):
        start = time.perf_counter()
        observation = robot.get_observation()
        action = robot.send_action(policy.act(observation))
        before = time.perf_counter()
        observer.step(k * PERIOD_S, observation, action)
        timings.observer_s.append(time.perf_counter() - before)
        busy = time.perf_counter() - start
        timings.busy_s.append(busy)
        timings.late += busy > PERIOD_S
        tick += PERIOD_S
        time.sleep(max(0.0, tick - time.perf_counter()))
    outcome = Outcome(success=False, steps=steps, path_length=0.0, scene_after=robot.read_scene(), duration_s=0.0)
    start = time.perf_counter()
    observer.end(scored(trial, outcome, 0.0, 0.0))
    timings.start_end_s.append(between + time.perf_counter() - start)


def print_table(bare: Timings, others: list[Timings]) -> None:
    print(f"one core (cpu {CPU}); {len(bare.busy_s)} steps per variant at {1 / PERIOD_S:.0f} Hz; times per step")
    header = f"{'variant':<10}{'busy ms':>9}{'p95 ms':>8}{'observer ms':>13}{'overhead ms':>13}{'of period':>11}"
    print(header + f"{'late':>6}{'start+end ms':>14}")
    for t in [bare, *others]:
        overhead = t.busy_ms() - bare.busy_ms()
        between = 1000 * float(np.mean(t.start_end_s))
        print(
            f"{t.name:<10}{t.busy_ms():>9.2f}{1000 * np.percentile(t.busy_s, 95):>8.2f}"
            f"{1000 * np.mean(t.observer_s):>13.3f}{overhead:>13.3f}{overhead / (1000 * PERIOD_S):>11.4f}"
            f"{t.late:>6}{between:>14.1f}"
        )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=4, help="timed episodes per variant")
    parser.add_argument("--steps", type=int, default=40, help="control steps per episode")
    parser.add_argument("--seed", type=int, default=0, help="seed of the instance sampler")
    args = parser.parse_args(argv)
    task = LanguageTableTask(families=("block2block",))
    instances = task.sample(args.episodes + 1, np.random.default_rng(args.seed))
    robot = LanguageTableSim(LanguageTableSimConfig())
    robot.connect()
    with tempfile.TemporaryDirectory() as tmp:
        variants = {
            "bare": QuietObserver(),
            "rerun": RerunEpisodeRecorder(Path(tmp) / "rerun_run", task=task),
            "dataset": DatasetRecorder(Path(tmp) / "dataset_run", fps=int(1 / PERIOD_S)),
        }
        timings = {name: Timings(name) for name in variants}
        for name, observer in variants.items():  # warm-up: imports, encoders, first files
            run_episode(robot, task, context(0, instances[0]), observer, 5, Timings(name))
        for episode, instance in enumerate(instances[1:], start=1):
            for name, observer in variants.items():
                run_episode(robot, task, context(episode, instance), observer, args.steps, timings[name])
        for observer in variants.values():
            observer.close()
    bare, rerun, dataset = timings["bare"], timings["rerun"], timings["dataset"]
    print_table(bare, [rerun, dataset])
    period_ms = 1000 * PERIOD_S
    rerun_ms, dataset_ms = rerun.busy_ms() - bare.busy_ms(), dataset.busy_ms() - bare.busy_ms()
    print(
        f"rerun_overhead_frac={rerun_ms / period_ms:.4f} dataset_overhead_frac={dataset_ms / period_ms:.4f} "
        f"rerun_overhead_ms={rerun_ms:.3f} dataset_overhead_ms={dataset_ms:.3f} bare_step_ms={bare.busy_ms():.3f} "
        f"rerun_start_end_ms={1000 * np.mean(rerun.start_end_s):.1f} "
        f"dataset_start_end_ms={1000 * np.mean(dataset.start_end_s):.1f}"
    )


if __name__ == "__main__":
    main()
