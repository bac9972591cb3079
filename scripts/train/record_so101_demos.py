"""Record demonstrations on the virtual SO-101 as a user would: start the twin, run `lerobot-record` with the scripted
demonstrator (`--teleop.type=so101_demo`), and check that the LeRobotDataset it wrote loads. The same seed remakes the
same placements; an interrupted recording is resumed where it stopped by running the same command again.

    python scripts/train/record_so101_demos.py --seed=0 --episodes=100 --output=DIR
        [--task="put the red cube in the left bin"] [--episode_time_s=12] [--reset_time_s=1] [--width=320 --height=240]
        [--fps=30] [--pace=1.5] [--tries=5] [--video] [--shards=1]

With `--shards=N`, N twins record N parts of the episodes side by side (each `lerobot-record` keeps to the clock, so
two cores hold two), into `OUTPUT.shards/episodes_FIRST-LAST`; LeRobot's `aggregate_datasets` then joins them into
OUTPUT in episode order. Every episode keeps its placement whatever N is.

Frames are stored as images in the dataset's parquet files unless `--video` is given: training on a CPU decodes a frame
per sample, and a PNG of a small frame decodes far faster than a seek into an AV1 video.

Prints `episodes=.. frames=.. seconds_per_episode=..` last."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shlex
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from lerobot_contrast.spine.flags import ScriptParser

REPO_ID = "local/so101_demos"


def recorded(output: Path) -> int:
    """Episodes already in the dataset at `output` (0: none yet)."""
    info = output / "meta" / "info.json"
    return json.loads(info.read_text())["total_episodes"] if info.is_file() else 0


def shards(args: argparse.Namespace) -> list[tuple[Path, int, int]]:
    """Each part's (dataset folder, first episode, episodes): the whole dataset itself when there is one part."""
    if args.shards == 1:
        return [(args.output, 0, args.episodes)]
    size, extra = divmod(args.episodes, args.shards)
    parts, first = [], 0
    for k in range(args.shards):
        count = size + (k < extra)
        parts.append((shard_root(args.output) / f"episodes_{first}-{first + count - 1}", first, count))
        first += count
    return parts


def shard_root(output: Path) -> Path:
    return output.with_name(output.name + ".shards")


def record_command(args: argparse.Namespace, twin, root: Path, first: int, count: int) -> list[str]:
    lerobot_record = Path(sys.executable).with_name("lerobot-record")
    done = recorded(root)
    return [
        str(lerobot_record),
        *shlex.split(twin.robot_flags),
        "--teleop.type=so101_demo",
        f"--teleop.placement={twin.placement}",
        f"--teleop.seed={args.seed}",
        f"--teleop.first_episode={first + done}",
        f"--teleop.pace={args.pace}",
        f"--dataset.repo_id={REPO_ID}",
        f"--dataset.root={root}",
        f"--dataset.single_task={args.task}",
        f"--dataset.num_episodes={count - done}",
        f"--dataset.episode_time_s={args.episode_time_s}",
        f"--dataset.reset_time_s={args.reset_time_s}",
        f"--dataset.fps={args.fps}",
        f"--dataset.video={'true' if args.video else 'false'}",
        "--dataset.push_to_hub=false",
        "--play_sounds=false",
        f"--resume={'true' if (root / 'meta' / 'info.json').is_file() else 'false'}",
    ]


def record(args: argparse.Namespace, twin, root: Path, first: int, count: int) -> str | None:
    """Run lerobot-record until the part's episodes are in, resuming after a failed run: on a loaded machine the
    twin's bus sometimes misses LeRobot's 50 ms reply deadline, which stops lerobot-record (the saved episodes stay).
    None once they are all in; else why not, in words (a run that exits 0 short of its episodes included)."""
    status = 0
    for _ in range(args.tries):
        status = subprocess.run(record_command(args, twin, root, first, count)).returncode
        if recorded(root) >= count:
            return None
    if status != 0:
        return f"lerobot-record stopped ({status})"
    return f"lerobot-record saved {recorded(root)} of the {count} episodes of {root.name} in {args.tries} runs"


def record_parts(args: argparse.Namespace, flags: list[str]) -> str | None:
    """Record every unfinished part on a twin of its own, side by side; why the first part that fell short did
    (a signal's exit status is negative), else None."""
    from lerobot_contrast.twin.launch import running_twin

    todo = [part for part in shards(args) if recorded(part[0]) < part[2]]
    with contextlib.ExitStack() as stack:  # started one after another: each takes free ports of its own
        twins = [stack.enter_context(running_twin(*flags)) for _ in todo]
        with ThreadPoolExecutor(max_workers=max(len(todo), 1)) as pool:
            shortfalls = list(pool.map(lambda twin, part: record(args, twin, *part), twins, todo))
    return next((why for why in shortfalls if why is not None), None)


def join_parts(args: argparse.Namespace) -> None:
    """Aggregate the recorded parts into --output in episode order (written beside it, then moved into place, so an
    interrupted join leaves no half dataset), then drop the parts."""
    from lerobot.datasets.aggregate import aggregate_datasets

    roots = [root for root, _, _ in shards(args)]
    joining = args.output.with_name(args.output.name + ".joining")
    shutil.rmtree(joining, ignore_errors=True)
    aggregate_datasets([REPO_ID] * len(roots), REPO_ID, roots=roots, aggr_root=joining)
    joining.rename(args.output)
    shutil.rmtree(shard_root(args.output))


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="the cubes' placements, episode by episode")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--output", type=Path, required=True, help="the dataset's folder")
    parser.add_argument("--task", default="put the red cube in the left bin", help="an so101_blocks instruction")
    parser.add_argument("--episode_time_s", type=float, default=12.0)
    parser.add_argument("--reset_time_s", type=float, default=1.0)
    parser.add_argument("--fps", type=int, default=30)
    parser.add_argument("--pace", type=float, default=1.5, help="the demonstrator's motion times, times the planned")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument("--video", action="store_true", help="encode frames as AV1 videos (LeRobot's default)")
    parser.add_argument("--tries", type=int, default=5, help="lerobot-record runs, each resuming, before giving up")
    parser.add_argument("--shards", type=int, default=1, help="twins recording parts of the episodes side by side")
    args = parser.parse_args(argv)
    if args.episodes < 1 or args.episode_time_s <= 0 or args.reset_time_s < 0 or args.pace <= 0:
        parser.error("--episodes must be at least 1, --episode_time_s and --pace above 0, --reset_time_s at least 0")
    if not 1 <= args.shards <= args.episodes:
        parser.error(f"--shards={args.shards}: give from 1 to --episodes ({args.episodes}) twins")
    if args.output.exists() and not (args.output / "meta" / "info.json").is_file():
        parser.error(f"--output={args.output} exists but holds no LeRobot dataset; give a new folder")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    from lerobot_contrast.contrast.errors import UserError
    from lerobot_contrast.domains.task_file import load_task_file
    from lerobot_contrast.so101.plan import goal_of

    try:
        goal_of(load_task_file("so101_blocks"), args.task)  # before the twin starts: a typo is one line at once
    except UserError as error:
        print(f"error: --task: {error}", file=sys.stderr)
        return 2
    done = recorded(args.output)
    spent = 0.0
    if done < args.episodes:
        os.environ.setdefault("HF_HUB_OFFLINE", "1")
        flags = [f"--seed={args.seed}", f"--fps={args.fps}", f"--width={args.width}", f"--height={args.height}"]
        began = time.monotonic()
        try:
            short = record_parts(args, flags)
        except UserError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        if short is not None:
            print(f"error: {short}; run the same command again to go on", file=sys.stderr)
            return 1
        if args.shards > 1:
            join_parts(args)
        spent = time.monotonic() - began
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    dataset = LeRobotDataset(REPO_ID, root=args.output)
    new = dataset.num_episodes - done
    print(f"episodes={dataset.num_episodes} frames={dataset.num_frames} "
          f"seconds_per_episode={spent / new if new else 0:.1f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
