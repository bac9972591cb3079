"""Seconds from starting a command to its one-line error for a mistyped flag, for every command (goal: under 2 s).

Usage: .venv/bin/python scripts/bench_flag_errors.py [--repeats N]; the last line holds the figures as name=value."""

from __future__ import annotations

import argparse
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


def seconds_to_error(command: str, argv: list[str], expected: str) -> float:
    start = time.perf_counter()
    result = subprocess.run(
        [sys.executable, "-m", f"lerobot_contrast.{command}", *argv], capture_output=True, text=True, timeout=300
    )
    elapsed = time.perf_counter() - start
    if result.returncode != 2 or f"did you mean {expected}" not in result.stderr:
        raise SystemExit(f"{command}: expected a one-line error naming {expected}, got: {result.stderr.strip()!r}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    repeats = parser.parse_args().repeats
    figures = {}
    for command, (argv, expected) in TYPOS.items():
        times = [seconds_to_error(command, argv, expected) for _ in range(repeats)]
        figures[f"{command}_s"] = statistics.median(times)
        print(f"{command}: median {figures[f'{command}_s']:.2f} s over {repeats} runs", flush=True)
    print(" ".join(f"{name}={value:.2f}" for name, value in figures.items()))


if __name__ == "__main__":
    main()
