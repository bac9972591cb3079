"""A long simulated session (the oracle on the Language-Table simulator, i.i.d. trials) with Rerun and dataset
recording on, through the same robot, policy and observers as `python -m lerobot_contrast.eval`. Threads, open
files, RSS and seconds per trial are sampled as it goes: none of them should grow with the number of episodes.
Usage: python scripts/bench/soak.py [--trials 2000] [--every 100] [--output_dir DIR]. The last line is machine-readable.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
import tempfile
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from lerobot_contrast.eval import connect, equipped, planned_evaluation
from lerobot_contrast.policies import make_policy
from lerobot_contrast.policies.base import PolicyArgs
from lerobot_contrast.record.observer import EpisodeFiles, QuietObserver
from lerobot_contrast.spine.build import make_robot, register_robots
from lerobot_contrast.spine.config import EvalConfig
from lerobot_contrast.spine.evaluation import run

WARM_UP = 5  # trials before the first sample: the first episodes load codecs and create the dataset


def threads() -> int:
    return len(os.listdir("/proc/self/task"))


def open_files() -> int:
    return len(os.listdir("/proc/self/fd"))


def rss_mb() -> float:
    with open("/proc/self/status", encoding="ascii") as status:
        kb = next(int(line.split()[1]) for line in status if line.startswith("VmRSS:"))
    return kb / 1024


@dataclass
class Sample:
    trials: int
    threads: int
    fds: int
    rss_mb: float


@dataclass
class Sampler(QuietObserver):
    """Watches the run after the recorders (so their files of the episode are closed): the resources held after
    each episode, and when each one ended."""

    every: int
    total: int
    samples: list[Sample] = field(default_factory=list)
    ends: list[float] = field(default_factory=list)

    def end(self, record) -> EpisodeFiles:
        self.ends.append(time.perf_counter())
        done = len(self.ends)
        if done in (WARM_UP, self.total) or done % self.every == 0:
            sample = Sample(done, threads(), open_files(), rss_mb())
            self.samples.append(sample)
            names = Counter(
                Path(f"/proc/self/task/{task}/comm").read_text().strip() for task in os.listdir("/proc/self/task")
            )
            busiest = ", ".join(f"{name} {count}" for name, count in names.most_common(3))
            print(
                f"trial {done}: threads={sample.threads} ({busiest}) fds={sample.fds} rss_mb={sample.rss_mb:.0f}",
                flush=True,
            )
        return EpisodeFiles()


def soak(trials: int, every: int, run_dir: Path, seed: int) -> Sampler:
    """Run `trials` recorded episodes into `run_dir` and return what was sampled along the way."""
    cfg = EvalConfig(
        strategy="standard", n_instances=trials, seed=seed, policy=PolicyArgs(type="oracle"),
        rerun=True, record_dataset=True, output_dir=run_dir,
    )  # fmt: skip
    register_robots()
    planned = planned_evaluation(cfg)
    robot = make_robot(cfg)
    connect(robot)
    sampler = Sampler(every, trials)
    try:
        policy = make_policy(cfg.policy, robot, planned.task, cfg.rename_map)
        evaluation = equipped(cfg, planned, robot, policy, None)
        evaluation = dataclasses.replace(evaluation, observers=[*evaluation.observers, sampler], verbose=False)
        run(evaluation)
    finally:
        robot.disconnect()
    return sampler


def seconds_per_trial(ends: Sequence[float], first: bool, n: int = 100) -> float:
    """Mean seconds per trial over the first (after warm-up) or last `n` trials."""
    window = ends[WARM_UP - 1 : WARM_UP + n] if first else ends[-n - 1 :]
    return (window[-1] - window[0]) / (len(window) - 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=2000)
    parser.add_argument("--every", type=int, default=100, help="sample every N trials")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--output_dir", type=Path, default=None, help="keep the run here (default: a temp dir)")
    args = parser.parse_args()
    if args.trials < WARM_UP + 2:
        parser.error(f"--trials must be at least {WARM_UP + 2}")
    scratch = None if args.output_dir else tempfile.mkdtemp(prefix="soak-")
    run_dir = args.output_dir or Path(scratch) / "run"
    try:
        sampler = soak(args.trials, args.every, run_dir, args.seed)
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    start, end = sampler.samples[0], sampler.samples[-1]
    n = min(100, (len(sampler.ends) - WARM_UP) // 2)  # a short soak compares its two halves
    print(
        f"trials={len(sampler.ends)} threads_start={start.threads} threads_end={end.threads} "
        f"fds_start={start.fds} fds_end={end.fds} rss_mb_start={start.rss_mb:.0f} rss_mb_end={end.rss_mb:.0f} "
        f"s_per_trial_first100={seconds_per_trial(sampler.ends, True, n):.3f} "
        f"s_per_trial_last100={seconds_per_trial(sampler.ends, False, n):.3f}"
    )


if __name__ == "__main__":
    main()
