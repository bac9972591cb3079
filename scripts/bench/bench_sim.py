"""Language-Table sim speed on one CPU core: env steps/s with the camera image and without, vs the benchmark.

Also times the whole evaluation loop in episodes per minute.
Usage: python scripts/bench/bench_sim.py [--episodes 30] [--seed 0] [--eval_instances 25]. The last line is machine-readable.
"""

from __future__ import annotations

import os

# One core, one BLAS thread: the figure should not depend on how many cores the machine has.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
CPU = min(os.sched_getaffinity(0))
os.sched_setaffinity(0, {CPU})

import argparse  # noqa: E402
import contextlib  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from lerobot_contrast.contrast.instance import Instance  # noqa: E402
from lerobot_contrast.domains.language_table import LanguageTableTask  # noqa: E402
from lerobot_contrast.domains.language_table.env import LanguageTableEnv  # noqa: E402
from lerobot_contrast.domains.language_table.oracle import PushOracle  # noqa: E402
from lerobot_contrast.eval import main as eval_main  # noqa: E402

# The benchmark's pybullet env takes ~46 ms per step on one core, render dominated (spec section 1.3).
PYBULLET_STEPS_PER_S = 21.7


@dataclass(frozen=True)
class Timing:
    obs_type: str  # what was timed: an env obs_type, or the oracle
    episodes: int
    steps: int
    seconds: float

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.seconds

    @property
    def ms_per_step(self) -> float:
        return 1000 * self.seconds / self.steps


def oracle_actions(task: LanguageTableTask, instances: list[Instance]) -> tuple[list[list[np.ndarray]], Timing]:
    """The noise-free oracle's actions for each instance (timed runs replay them), and the oracle's own cost."""
    env, oracle, plans, seconds = LanguageTableEnv(obs_type="state"), PushOracle(task), [], 0.0
    for instance in instances:
        obs, _ = env.reset(options={"instance": instance})
        oracle.reset(instance)
        actions = []
        for _ in range(env._max_episode_steps):
            start = time.perf_counter()
            actions.append(oracle.act(env.scene(), obs["effector_target_translation"]))
            seconds += time.perf_counter() - start
            obs, _, terminated, _, _ = env.step(actions[-1])
            if terminated:
                break
        plans.append(actions)
    return plans, Timing("oracle act", len(instances), sum(map(len, plans)), seconds)


def time_env(obs_type: str, instances: list[Instance], plans: list[list[np.ndarray]]) -> Timing:
    """Wall time of env.step (physics, observation, success check and, for "rgb", rendering) only."""
    env, steps, seconds = LanguageTableEnv(obs_type=obs_type), 0, 0.0
    for instance, actions in zip(instances, plans, strict=True):
        env.reset(options={"instance": instance})
        start = time.perf_counter()
        for action in actions:
            env.step(action)
        seconds += time.perf_counter() - start
        steps += len(actions)
    return Timing(obs_type, len(instances), steps, seconds)


def print_table(timings: list[Timing]) -> None:
    print(f"one core (cpu {CPU}); oracle-driven episodes of sampled BLOCK_8 instances; env rows time env.step only")
    print(f"{'timed':<12}{'episodes':>10}{'steps':>8}{'ms/step':>10}{'steps/s':>10}{'vs pybullet':>13}")
    for t in timings:
        ratio = t.steps_per_s / PYBULLET_STEPS_PER_S
        print(
            f"{t.obs_type:<12}{t.episodes:>10}{t.steps:>8}{t.ms_per_step:>10.3f}{t.steps_per_s:>10.0f}{ratio:>12.0f}x"
        )


def time_evaluation(n_instances: int, seed: int) -> Timing:
    """The whole `lerobot_contrast.eval` loop (contrast strategy, oracle, SPL references, journal) per episode."""
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()):
        start = time.perf_counter()
        eval_main([f"--n_instances={n_instances}", f"--seed={seed}", "--rerun=false", f"--output_dir={tmp}/run"])
        seconds = time.perf_counter() - start
        overall = json.loads((Path(tmp) / "run" / "summary.json").read_text())["overall"]
    return Timing("evaluation", overall["trials"], overall["trials"], seconds)


def summary_line(rgb: Timing, state: Timing, evaluation: Timing) -> str:
    return (
        f"steps_per_s_rgb={rgb.steps_per_s:.1f} steps_per_s_state={state.steps_per_s:.1f} "
        f"ratio_rgb_vs_pybullet={rgb.steps_per_s / PYBULLET_STEPS_PER_S:.1f} "
        f"episodes_per_min={60 * evaluation.episodes / evaluation.seconds:.1f}"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=30, help="sampled instances, each run once per obs_type")
    parser.add_argument("--seed", type=int, default=0, help="seed of the instance sampler")
    parser.add_argument("--eval_instances", type=int, default=25, help="base instances of the timed evaluation")
    args = parser.parse_args(argv)
    task = LanguageTableTask(block_mode="BLOCK_8")
    instances = task.sample(args.episodes, np.random.default_rng(args.seed))
    plans, oracle = oracle_actions(task, instances)
    time_env("rgb", instances[:2], plans[:2])  # warm-up: imports, renderer layouts, caches
    rgb, state = time_env("rgb", instances, plans), time_env("state", instances, plans)
    print_table([rgb, state, oracle])
    evaluation = time_evaluation(args.eval_instances, args.seed)
    print(
        f"evaluation loop: {evaluation.episodes} episodes in {evaluation.seconds:.1f} s "
        f"(contrast strategy, {args.eval_instances} base instances, oracle policy, SPL references, journal)"
    )
    print(summary_line(rgb, state, evaluation))


if __name__ == "__main__":
    main()
