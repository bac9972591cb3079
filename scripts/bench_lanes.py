"""Time the same simulated evaluation with one lane and with many, in one process, and check that the journals agree
trial for trial (up to wall-clock fields). Figures last: trials=... wall_1lane_s=... wall_lanes_s=... speedup=...
identical=true|false.

    .venv/bin/python scripts/bench_lanes.py                      # the default evaluation (the README's first command)
    .venv/bin/python scripts/bench_lanes.py --n_instances=10 --lanes=4 --busy   # beside a process that keeps a core busy
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import resource
import sys
import tempfile
import time
from pathlib import Path

# Fields that say when and how long, which no two runs share.
WALL_CLOCK = ("started_at", "duration_s")


def journal(run_dir: Path) -> list[dict]:
    rows = [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines() if line.strip()]
    return [{k: v for k, v in row.items() if k not in WALL_CLOCK} for row in rows]


def timed_run(flags: list[str], run_dir: Path) -> float:
    from lerobot_contrast.eval import main

    start = time.perf_counter()
    code = main([*flags, f"--output_dir={run_dir}"])
    if code != 0:
        sys.exit(f"bench_lanes: the evaluation exited with {code}")
    return time.perf_counter() - start


def spin(stop: float) -> None:
    while time.time() < stop:
        pass


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lanes", default="auto", help="lanes of the second run (default: the evaluation's auto)")
    parser.add_argument("--n_instances", type=int, default=None, help="default: the task's own (the default eval)")
    parser.add_argument("--busy", action="store_true", help="keep one core busy with another process meanwhile")
    args, flags = parser.parse_known_args()
    flags = [*flags, *([f"--n_instances={args.n_instances}"] if args.n_instances else [])]
    from lerobot_contrast.eval import main as warm  # imports and weights load before anything is timed

    with tempfile.TemporaryDirectory() as tmp:
        warm([*flags, "--n_instances=1", "--max_episode_steps=2", f"--output_dir={tmp}/warm"])
        busy = None
        if args.busy:
            busy = multiprocessing.get_context("spawn").Process(target=spin, args=(time.time() + 24 * 3600,))
            busy.start()
        try:
            one = timed_run([*flags, "--lanes=1"], Path(tmp) / "one")
            many = timed_run([*flags, f"--lanes={args.lanes}"], Path(tmp) / "many")
        finally:
            if busy is not None:
                busy.terminate()
        a, b = journal(Path(tmp) / "one"), journal(Path(tmp) / "many")
    differing = next((i for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y), None)
    if differing is not None:
        print(f"first differing trial: {differing}\n  1 lane: {a[differing]}\n  lanes:  {b[differing]}")
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"trials={len(a)} lanes={args.lanes} busy={str(args.busy).lower()} wall_1lane_s={one:.1f} "
        f"wall_lanes_s={many:.1f} speedup={one / many:.2f} peak_rss_mb={rss_mb:.0f} "
        f"identical={str(a == b).lower()}"
    )


if __name__ == "__main__":
    main()
