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
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# Fields that say when and how long, which no two runs share.
WALL_CLOCK = ("started_at", "duration_s")


def journal(run_dir: Path) -> list[dict]:
    rows = [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines() if line.strip()]
    return [{k: v for k, v in row.items() if k not in WALL_CLOCK} for row in rows]


def timed_run(flags: list[str], run_dir: Path) -> tuple[float, float]:
    """Wall and CPU seconds (all of the process's threads) of one evaluation: on a shared machine the CPU time is
    the fair comparison, as the share of the cores the run gets changes while it runs."""
    from lerobot_contrast.eval import main

    start, cpu = time.perf_counter(), time.process_time()
    code = main([*flags, f"--output_dir={run_dir}"])
    if code != 0:
        sys.exit(f"bench_lanes: the evaluation exited with {code}")
    return time.perf_counter() - start, time.process_time() - cpu


# CPU feature sets a machine may give torch's own kernels, oneDNN's convolutions and MKL's matrix products.
FEATURE_SETS = {
    "aten_default": {"ATEN_CPU_CAPABILITY": "default"},
    "onednn_sse41": {"ONEDNN_MAX_CPU_ISA": "SSE41"},
    "mkl_compatible": {"MKL_CBWR": "COMPATIBLE"},
    "all_baseline": {"ATEN_CPU_CAPABILITY": "default", "ONEDNN_MAX_CPU_ISA": "SSE41", "MKL_CBWR": "COMPATIBLE"},
}


def feature_set_runs(flags: list[str], tmp: Path) -> list[str]:
    """Run the evaluation as this CPU would on machines with fewer features; per feature set, how many trials
    differ from this machine's and by how much the overall success and SPL move."""
    native = _subprocess_run(flags, tmp / "native", {})
    figures = []
    for name, env in FEATURE_SETS.items():
        other = _subprocess_run(flags, tmp / name, env)
        a, b = journal(tmp / "native"), journal(tmp / name)
        differing = sum(x != y for x, y in zip(a, b, strict=False)) + abs(len(a) - len(b))
        moved = {k: abs(native[k] - other[k]) for k in ("success", "spl")}
        figures.append(
            f"{name}_differing={differing} {name}_dsuccess={moved['success']:.3f} {name}_dspl={moved['spl']:.3f}"
        )
    return figures


def _subprocess_run(flags: list[str], run_dir: Path, env: dict[str, str]) -> dict[str, float]:
    command = [sys.executable, "-m", "lerobot_contrast.eval", *flags, f"--output_dir={run_dir}"]
    subprocess.run(command, env={**os.environ, **env}, check=True, stdout=subprocess.DEVNULL)
    overall = json.loads((run_dir / "summary.json").read_text())["overall"]
    return {"success": overall["success_rate"], "spl": overall["spl"]}


def spin(stop: float) -> None:
    while time.time() < stop:
        pass


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lanes", default="8", help="lanes of the second run (default: 8)")
    parser.add_argument("--n_instances", type=int, default=None, help="default: the task's own (the default eval)")
    parser.add_argument("--busy", action="store_true", help="keep one core busy with another process meanwhile")
    parser.add_argument("--feature_sets", action="store_true", help="instead: compare runs under CPU feature sets")
    args, flags = parser.parse_known_args()
    flags = [*flags, *([f"--n_instances={args.n_instances}"] if args.n_instances else [])]
    if args.feature_sets:
        with tempfile.TemporaryDirectory() as tmp:
            print(" ".join(feature_set_runs(flags, Path(tmp))))
        return
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
        f"trials={len(a)} lanes={args.lanes} busy={str(args.busy).lower()} cpu_1lane_s={one[1]:.1f} "
        f"cpu_lanes_s={many[1]:.1f} cpu_speedup={one[1] / many[1]:.2f} peak_rss_mb={rss_mb:.0f} "
        f"wall_1lane_s={one[0]:.1f} wall_lanes_s={many[0]:.1f} speedup={one[0] / many[0]:.2f} "
        f"identical={str(a == b).lower()}"
    )


if __name__ == "__main__":
    main()
