"""Time the same simulated evaluation with one lane and with many, in one process, and check that the journals agree
trial for trial (up to wall-clock fields). Figures last: trials=... wall_1lane_s=... wall_lanes_s=... speedup=...
identical=true|false (the journals to the last digit) same_outcomes=true|false (each trial's status and success).

    .venv/bin/python scripts/bench/bench_lanes.py                      # the default evaluation (the README's first command)
    .venv/bin/python scripts/bench/bench_lanes.py --n_instances=10 --busy   # the lanes alone, then beside busy processes

With --busy the figures are the lanes' run alone and beside processes that keep cores busy: its share of a core
(CPU-s per wall-s), its throughput (trials per wall-s) and CPU-s per trial in each, and `proportional`, the ratio
of throughputs over the ratio of shares (1.0: it slows exactly in proportion to the share it gets).
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


def busy_runs(flags: list[str], lanes: str, spinners: int, tmp: Path) -> str:
    """The lanes' evaluation alone and beside `spinners` processes that keep a core busy each, as name=value pairs."""
    alone = timed_run([*flags, f"--lanes={lanes}"], tmp / "alone")
    context = multiprocessing.get_context("spawn")
    busy = [context.Process(target=spin, args=(time.time() + 24 * 3600,)) for _ in range(spinners)]
    for process in busy:
        process.start()
    try:
        beside = timed_run([*flags, f"--lanes={lanes}"], tmp / "busy")
    finally:
        for process in busy:
            process.terminate()
    trials = len(journal(tmp / "alone"))
    identical = journal(tmp / "alone") == journal(tmp / "busy")
    share = [cpu / wall for wall, cpu in (alone, beside)]
    throughput = [trials / wall for wall, _ in (alone, beside)]
    return (
        f"trials={trials} lanes={lanes} spinners={spinners} wall_alone_s={alone[0]:.1f} wall_busy_s={beside[0]:.1f} "
        f"share_alone={share[0]:.2f} share_busy={share[1]:.2f} cpu_per_trial_alone_s={alone[1] / trials:.3f} "
        f"cpu_per_trial_busy_s={beside[1] / trials:.3f} throughput_ratio={throughput[1] / throughput[0]:.2f} "
        f"share_ratio={share[1] / share[0]:.2f} proportional={throughput[1] / throughput[0] / (share[1] / share[0]):.2f} "
        f"identical={str(identical).lower()}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lanes", default="8", help="lanes of the second run (default: 8)")
    parser.add_argument("--n_instances", type=int, default=None, help="default: the task's own (the default eval)")
    parser.add_argument(
        "--busy",
        type=int,
        nargs="?",
        const=1,
        default=0,
        help="instead: the lanes alone, then beside this many processes that keep a core busy each (default 1)",
    )
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
        if args.busy:
            print(busy_runs(flags, args.lanes, args.busy, Path(tmp)))
            return
        one = timed_run([*flags, "--lanes=1"], Path(tmp) / "one")
        many = timed_run([*flags, f"--lanes={args.lanes}"], Path(tmp) / "many")
        a, b = journal(Path(tmp) / "one"), journal(Path(tmp) / "many")
    differing = next((i for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y), None)
    if differing is not None:
        print(f"first differing trial: {differing}\n  1 lane: {a[differing]}\n  lanes:  {b[differing]}")
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"trials={len(a)} lanes={args.lanes} cpu_1lane_s={one[1]:.1f} "
        f"cpu_lanes_s={many[1]:.1f} cpu_speedup={one[1] / many[1]:.2f} peak_rss_mb={rss_mb:.0f} "
        f"wall_1lane_s={one[0]:.1f} wall_lanes_s={many[0]:.1f} speedup={one[0] / many[0]:.2f} "
        f"identical={str(a == b).lower()} same_outcomes={str(outcomes(a) == outcomes(b)).lower()}"
    )


def outcomes(rows: list[dict]) -> list[tuple]:
    """Each trial's status and success: what the lanes promise on any CPU, where its kernels may round a batch's rows
    otherwise than one row's in the last bits (docs/development.md)."""
    return [(row["index"], row["status"], row.get("success")) for row in rows]


if __name__ == "__main__":
    main()
