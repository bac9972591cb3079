"""Train LeRobot's ACT on demonstrations recorded on the virtual SO-101, with `lerobot-train` as a user runs it,
sized for a CPU. Run it again after a kill and it resumes from the last checkpoint; run it with more `--steps` and it
trains on from there.

    python scripts/train/train_so101_act.py --dataset=DIR --output=DIR [--steps=6000] [--batch_size=16] [--save_freq=500]
        [--seed=1000] [-- more lerobot-train flags]

The recipe and why: lerobot_contrast/training/act_recipe.py (the same network scripts/bench/bench_twin.py times).

Prints `steps=.. wall_s=.. steps_per_s=.. checkpoint=.. checkpoint_mb=..` last."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from lerobot_contrast.spine.flags import ScriptParser
from lerobot_contrast.training import act_recipe

REPO_ID = "local/so101_demos"
RECIPE = (
    "--policy.type=act",
    "--policy.device=cpu",
    "--policy.push_to_hub=false",
    *act_recipe.policy_flags(),
    "--wandb.enable=false",
    "--env_eval_freq=0",
    "--log_freq=50",
)


def last_checkpoint(output: Path) -> Path | None:
    last = output / "checkpoints" / "last" / "pretrained_model"
    return last if (last / "train_config.json").is_file() else None


def trained_steps(output: Path) -> int:
    """The step the last checkpoint saved (0: none yet)."""
    last = last_checkpoint(output)
    if last is None:
        return 0
    return json.loads((last.parent / "training_state" / "training_step.json").read_text())["step"]


def train_command(args: argparse.Namespace, extra: list[str]) -> list[str]:
    lerobot_train = str(Path(sys.executable).with_name("lerobot-train"))
    last = last_checkpoint(args.output)
    if last is not None:  # LeRobot's own resume: the config, optimizer, scheduler and data order from the checkpoint
        return [lerobot_train, f"--config_path={last / 'train_config.json'}", "--resume=true",
                f"--steps={args.steps}", *extra]  # fmt: skip
    return [
        lerobot_train,
        f"--dataset.repo_id={REPO_ID}",
        f"--dataset.root={args.dataset}",
        f"--output_dir={args.output}",
        f"--steps={args.steps}",
        f"--batch_size={args.batch_size}",
        f"--save_freq={args.save_freq}",
        f"--num_workers={args.num_workers}",
        f"--seed={args.seed}",
        *RECIPE,
        *extra,
    ]


def parse_args(argv: list[str] | None = None) -> tuple[argparse.Namespace, list[str]]:
    argv = list(sys.argv[1:] if argv is None else argv)
    extra = argv[argv.index("--") + 1 :] if "--" in argv else []
    argv = argv[: argv.index("--")] if "--" in argv else argv
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", type=Path, required=True, help="the LeRobotDataset record_so101_demos.py wrote")
    parser.add_argument("--output", type=Path, required=True, help="lerobot-train's output directory")
    parser.add_argument("--steps", type=int, default=6000, help="total gradient steps, counting those already done")
    parser.add_argument("--batch_size", type=int, default=16)
    parser.add_argument("--save_freq", type=int, default=500, help="steps between checkpoints (what a kill loses)")
    parser.add_argument("--num_workers", type=int, default=1)
    parser.add_argument("--seed", type=int, default=1000)
    args = parser.parse_args(argv)
    if args.steps < 1 or args.batch_size < 1 or args.save_freq < 1 or args.num_workers < 0:
        parser.error("--steps, --batch_size and --save_freq must be at least 1, --num_workers at least 0")
    if not (args.dataset / "meta" / "info.json").is_file():
        parser.error(f"--dataset={args.dataset} holds no LeRobot dataset; record one with record_so101_demos.py")
    if args.output.exists() and last_checkpoint(args.output) is None:
        parser.error(f"--output={args.output} exists but holds no lerobot-train checkpoint; give a new folder")
    return args, extra


def main(argv: list[str] | None = None) -> int:
    args, extra = parse_args(argv)
    os.environ.setdefault("HF_HUB_OFFLINE", "1")  # a local dataset; nothing is fetched
    done = trained_steps(args.output)
    began = time.monotonic()
    if done < args.steps:
        status = subprocess.run(train_command(args, extra)).returncode
        if status != 0:
            print(f"error: lerobot-train stopped ({status}); run the same command again to resume", file=sys.stderr)
            return 1
    spent = time.monotonic() - began
    now = trained_steps(args.output)
    checkpoint = last_checkpoint(args.output)
    size = sum(f.stat().st_size for f in checkpoint.iterdir() if f.is_file()) / 1e6 if checkpoint else 0.0
    print(f"steps={now} wall_s={spent:.0f} steps_per_s={(now - done) / spent if now > done else 0:.3f} "
          f"checkpoint={checkpoint} checkpoint_mb={size:.1f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
