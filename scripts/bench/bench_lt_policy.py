"""Language-Table policy speed and memory on CPU: `select_action` at batch 1 (instruction embedding cached) and the
whole 10 Hz control step (render + preprocess + select_action + postprocess + sim step), against the 100 ms period.

The policy is full size (CLIP ViT-B/16 text tower), random weights in the released shapes, written by this script in
LeRobot's pretrained format; it is loaded and timed in a fresh process, whose peak memory is reported.
Usage: python scripts/bench/bench_lt_policy.py [--steps 60] [--threads 1]. The last line is machine-readable.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PERIOD_MS = 100.0  # the benchmark's 10 Hz control loop
INSTRUCTION = "push the red moon to the top left corner"


def write_policy(out_dir: Path) -> None:
    """A full-size policy with PyTorch's default random init and plausible action statistics."""
    import torch
    from lerobot_policy_language_table import (
        LanguageTableConfig,
        LanguageTablePolicy,
        make_language_table_pre_post_processors,
    )

    torch.manual_seed(0)
    config = LanguageTableConfig(device="cpu")
    LanguageTablePolicy(config).save_pretrained(out_dir)
    stats = {"action": {"mean": torch.zeros(2), "std": torch.full((2,), 0.02)}}
    for pipeline in make_language_table_pre_post_processors(config, dataset_stats=stats):
        pipeline.save_pretrained(out_dir)


def _rss_mb() -> float:
    with open("/proc/self/status") as f:
        kib = next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))
    return kib / 1024


def measure(policy_dir: str, steps: int, threads: int) -> dict:
    """Runs in the child process: load the policy, drive the simulator, time both, read the peak memory."""
    import gymnasium
    import torch
    from lerobot.policies import make_pre_post_processors
    from lerobot.policies.utils import prepare_observation_for_inference
    from lerobot_policy_language_table import LanguageTablePolicy

    import lerobot_contrast.domains.language_table.env  # noqa: F401  (registers the env id)

    torch.set_num_threads(threads)
    before_mb = _rss_mb()
    start = time.perf_counter()
    policy = LanguageTablePolicy.from_pretrained(policy_dir)
    pre, post = make_pre_post_processors(policy.config, pretrained_path=policy_dir)
    load_s = time.perf_counter() - start
    env = gymnasium.make("lerobot_contrast/LanguageTable-v0", obs_type="rgb")
    obs, _ = env.reset(seed=0)
    policy.reset()
    select_ms, step_ms = [], []
    for k in range(steps + 5):  # the first steps warm up allocators and embed the instruction
        t0 = time.perf_counter()
        observation = prepare_observation_for_inference(
            {"observation.images.top": obs["rgb"]}, torch.device("cpu"), task=INSTRUCTION
        )
        batch = pre(observation)
        t1 = time.perf_counter()
        action = policy.select_action(batch)
        t2 = time.perf_counter()
        obs, *_ = env.step(post(action)[0].numpy())
        t3 = time.perf_counter()
        if k >= 5:
            select_ms.append(1000 * (t2 - t1))
            step_ms.append(1000 * (t3 - t0))
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {
        "select_action_ms": statistics.median(select_ms),
        "select_action_p90_ms": statistics.quantiles(select_ms, n=10)[-1],
        "step_ms": statistics.median(step_ms),
        "peak_mb": peak_mb,
        "before_load_mb": before_mb,
        "load_s": load_s,
        "parameters": sum(p.numel() for p in policy.parameters()),
        "threads": threads,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=60, help="timed control steps (after 5 warm-up steps)")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    parser.add_argument("--measure", help=argparse.SUPPRESS)  # internal: the child process's policy directory
    args = parser.parse_args(argv)
    if args.measure:
        print(json.dumps(measure(args.measure, args.steps, args.threads)))
        return
    with tempfile.TemporaryDirectory() as tmp:
        write_policy(Path(tmp))
        cmd = [sys.executable, __file__, "--measure", tmp, "--steps", str(args.steps), "--threads", str(args.threads)]
        child = subprocess.run(cmd, capture_output=True, text=True, check=True, env=os.environ)
    r = json.loads(child.stdout.strip().splitlines()[-1])
    print(f"full-size policy, {r['parameters']:,} parameters, random weights; torch threads: {r['threads']}")
    print(f"load (from_pretrained + processors): {r['load_s']:.1f} s")
    print(
        f"select_action, batch 1, instruction cached: median {r['select_action_ms']:.1f} ms, p90 "
        f"{r['select_action_p90_ms']:.1f} ms ({r['select_action_ms'] / PERIOD_MS:.0%} of the 100 ms period)"
    )
    print(
        f"10 Hz step (render + preprocess + select_action + postprocess + sim): median {r['step_ms']:.1f} ms "
        f"({r['step_ms'] / PERIOD_MS:.0%} of the period)"
    )
    print(f"process memory: {r['before_load_mb']:.0f} MB after imports, peak {r['peak_mb']:.0f} MB with the policy")
    print(
        f"select_action_ms={r['select_action_ms']:.1f} step_ms={r['step_ms']:.1f} peak_mb={r['peak_mb']:.0f} "
        f"policy_mb={r['peak_mb'] - r['before_load_mb']:.0f} select_share={r['select_action_ms'] / PERIOD_MS:.2f} "
        f"step_share={r['step_ms'] / PERIOD_MS:.2f} threads={r['threads']}"
    )


if __name__ == "__main__":
    main()
