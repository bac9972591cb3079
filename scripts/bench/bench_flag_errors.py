"""Seconds from starting a command to its one-line error for a mistyped flag, for every command (goal: under 2 s on
an idle machine). Beside them, in the same run: a bare interpreter's start and the import of LeRobot's robots (torch),
which the check must not wait for, so `*_vs_lerobot` stays comparable across loads; the load average is printed too.

Usage: .venv/bin/python scripts/bench/bench_flag_errors.py [--repeats N]; the last line holds the figures as name=value."""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time

# Each command with a flag one letter off a real one; the error must name the real one.
TYPOS = {
    "eval": (["--n_instance=3"], "--n_instances"),
    "report": (["run", "--metrc=spl"], "--metric"),
    "review": (["run", "--save_onl=true"], "--save_only"),
    "publish": (["run", "--repo=u/n"], "--repo_id"),
    "sweep": (["sweep.yaml", "--max_retrie=2"], "--max_retries"),
}


def cpu_seconds() -> float:
    """CPU seconds of the finished child processes: on a busy machine the wall time stretches, this does not."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def seconds_to_error(command: str, argv: list[str], expected: str) -> tuple[float, float]:
    """Wall and CPU seconds from starting the command to its one-line error."""
    start, cpu = time.perf_counter(), cpu_seconds()
    result = subprocess.run(
        [sys.executable, "-m", f"lerobot_contrast.{command}", *argv], capture_output=True, text=True, timeout=300
    )
    elapsed = time.perf_counter() - start
    if result.returncode != 2 or f"did you mean {expected}" not in result.stderr:
        raise SystemExit(f"{command}: expected a one-line error naming {expected}, got: {result.stderr.strip()!r}")
    return elapsed, cpu_seconds() - cpu


def seconds_to_run(code: str) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    repeats = parser.parse_args().repeats
    load_before = os.getloadavg()[0]
    figures = {
        "python_s": statistics.median(seconds_to_run("pass") for _ in range(repeats)),
        "lerobot_robots_s": statistics.median(seconds_to_run("import lerobot.robots") for _ in range(repeats)),
    }
    for command, (argv, expected) in TYPOS.items():
        walls, cpus = zip(*(seconds_to_error(command, argv, expected) for _ in range(repeats)), strict=True)
        figures[f"{command}_s"], figures[f"{command}_cpu_s"] = statistics.median(walls), statistics.median(cpus)
        print(
            f"{command}: median {figures[f'{command}_s']:.2f} s ({figures[f'{command}_cpu_s']:.2f} CPU-s)", flush=True
        )
    slowest = max(figures[f"{command}_s"] for command in TYPOS)
    figures["slowest_s"] = slowest
    figures["slowest_vs_lerobot"] = slowest / figures["lerobot_robots_s"]
    figures["load_1min"] = (load_before + os.getloadavg()[0]) / 2
    print(f"bare python {figures['python_s']:.2f} s, import lerobot.robots {figures['lerobot_robots_s']:.2f} s")
    print(" ".join(f"{name}={value:.2f}" for name, value in figures.items()))


if __name__ == "__main__":
    main()
