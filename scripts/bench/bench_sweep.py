"""Benchmark of the sweep engine: the same simulated cells run one after another in this process (no Ray), then
as a sweep on a local Ray with 1 worker, then with 2 workers.

Usage: python scripts/bench/bench_sweep.py [--cells 8] [--n_instances 60] [--max_episode_steps 100]
The last line is `cells=... wall_1worker_s=... wall_2workers_s=... speedup=... overhead_per_cell_s=...`: speedup is
1 worker's wall time over 2 workers', and the overhead per cell is the 1-worker sweep's wall time less the
sequential one, per cell. The line before gives Ray's startup (not in the overhead) and inside_cells_1worker_s, the
time the 1-worker sweep's cells took in their worker (the first cell there pays the worker's imports); the line
before that what a cluster adds: carry_ms_per_cell, packing a cell's run directory on a node without the sweep
folder and unpacking it into the folder, and shipped_mb, this project's code as the nodes receive it. Goals on an
idle 2-core machine: speedup at least 1.7, overhead under 2 s per cell. Other load on the cores lowers the speedup.
The default cells take about 10 s each, a small evaluation; with much shorter cells each worker's one-time imports
(torch, LeRobot) weigh more and the speedup reads lower (4 cells of 16 instances: 1.37). About 3 minutes in all.
"""

from __future__ import annotations

import argparse
import logging
import tempfile
import time
from pathlib import Path

import ray
import yaml
from rich.console import Console

from lerobot_contrast.spine.build import register_robots
from lerobot_contrast.sweep.carry import pack, unpack
from lerobot_contrast.sweep.cells import read_sweep_file, sweep_cells
from lerobot_contrast.sweep.cluster import quiet_notes
from lerobot_contrast.sweep.command import SweepConfig, execute
from lerobot_contrast.sweep.shipping import shipped_paths
from lerobot_contrast.sweep.worker import run_cell


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cells", type=int, default=8)
    p.add_argument("--n_instances", type=int, default=60)
    p.add_argument("--max_episode_steps", type=int, default=100)
    return p.parse_args(argv)


def spec(args: argparse.Namespace) -> dict:
    """Contrast evaluations with the oracle, one cell per seed."""
    settings = {"n_instances": args.n_instances, "max_episode_steps": args.max_episode_steps, "rerun": False}
    return {"eval": {**settings, "policy": {"type": "oracle"}}, "grid": {"seed": list(range(args.cells))}}


def sequential(path: Path, out: Path) -> float:
    cells = sweep_cells(path, read_sweep_file(path), out)
    start = time.perf_counter()
    for cell in cells:
        outcome = run_cell(cell.name, cell.config)
        if outcome.status != "complete":
            raise SystemExit(f"error: {cell.name}: {outcome.error}")
    return time.perf_counter() - start


def on_ray(path: Path, out: Path, workers: int) -> tuple[float, float, float]:
    """Ray's startup, the sweep's wall time and the time spent inside the cells, on a local Ray with `workers`
    CPUs."""
    start = time.perf_counter()
    quiet_notes()
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING)
    started = time.perf_counter()
    try:
        outcomes = execute(SweepConfig(sweep=path, output_dir=out), read_sweep_file(path), Console(quiet=True))
    finally:
        ray.shutdown()
    for outcome in outcomes.values():
        if outcome.status != "complete":
            raise SystemExit(f"error: {outcome.name}: {outcome.error}")
    return started - start, time.perf_counter() - started, sum(o.seconds for o in outcomes.values())


def carried(out: Path) -> float:
    """Milliseconds per cell to pack its run directory and unpack it elsewhere, as a cell comes back from a node."""
    dirs = [d for d in out.iterdir() if (d / "journal.jsonl").is_file()]
    start = time.perf_counter()
    for run_dir in dirs:
        unpack(pack(run_dir), out.with_name("carried") / run_dir.name)
    return (time.perf_counter() - start) * 1000 / len(dirs)


def shipped_mb() -> float:
    files = [f for p in shipped_paths() for f in p.rglob("*") if f.is_file() and "__pycache__" not in f.parts]
    return sum(f.stat().st_size for f in files if f.suffix != ".pyc") / 1e6


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    register_robots()  # imports shared by every run below, paid once before timing
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.yaml"
        path.write_text(yaml.safe_dump(spec(args), sort_keys=False), encoding="utf-8")
        seq = sequential(path, Path(tmp) / "sequential")
        start_1, wall_1, inside_1 = on_ray(path, Path(tmp) / "one", 1)
        start_2, wall_2, _ = on_ray(path, Path(tmp) / "two", 2)
        carry_ms = carried(Path(tmp) / "one")
    print(f"carry_ms_per_cell={carry_ms:.1f} shipped_mb={shipped_mb():.2f}")
    print(
        f"sequential_s={seq:.1f} inside_cells_1worker_s={inside_1:.1f} ray_start_1worker_s={start_1:.1f} "
        f"ray_start_2workers_s={start_2:.1f}"
    )
    print(
        f"cells={args.cells} wall_1worker_s={wall_1:.1f} wall_2workers_s={wall_2:.1f} speedup={wall_1 / wall_2:.2f} "
        f"overhead_per_cell_s={(wall_1 - seq) / args.cells:.2f}"
    )


if __name__ == "__main__":
    main()
