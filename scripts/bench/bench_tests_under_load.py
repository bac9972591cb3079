"""The tests that drive the twin, run again and again beside processes that keep every core busy: on the simulated
clock their results must not depend on the machine's load (the few real-time tests, `-m realtime`, are left out:
they check what only an unloaded machine shows).

    .venv/bin/python scripts/bench/bench_tests_under_load.py [--runs=2] [--hogs=1] [--workers=2] [PATHS...]

Each run is `pytest -n WORKERS -m "not realtime" PATHS` (default: tests/twin tests/operators) beside HOGS busy
processes (a run took 5-7 minutes on this project's 2-core machine; `--runs=5`, as the twin's clock was checked with,
about 32); the last line: runs=... failed_runs=... failed_tests=... tests=... mean_run_s=... hogs=...
"""

from __future__ import annotations

import multiprocessing
import re
import subprocess
import sys
import time

from lerobot_contrast.spine.flags import ScriptParser

PATHS = ["tests/twin", "tests/operators"]


def hog() -> None:
    while True:
        pass


def main(argv: list[str] | None = None) -> int:
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--hogs", type=int, default=1, help="busy processes beside every run")
    parser.add_argument("--workers", type=int, default=2, help="pytest-xdist workers")
    parser.add_argument("paths", nargs="*", default=PATHS)
    args = parser.parse_args(argv)
    if min(args.runs, args.hogs, args.workers) < 1:
        parser.error("--runs, --hogs and --workers must be at least 1")
    hogs = [multiprocessing.get_context("spawn").Process(target=hog, daemon=True) for _ in range(args.hogs)]
    for process in hogs:
        process.start()
    failed_runs, failed, passed, seconds = 0, 0, 0, []
    try:
        for run in range(args.runs):
            began = time.monotonic()
            command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"-n={args.workers}",
                       "-m", "not realtime", *args.paths]  # fmt: skip
            done = subprocess.run(command, capture_output=True, text=True)
            seconds.append(time.monotonic() - began)
            tail = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr[-300:]
            print(f"run {run + 1}: exit {done.returncode} in {seconds[-1]:.0f} s: {tail}", flush=True)
            if done.returncode != 0:
                failed_runs += 1
                print("\n".join(line for line in done.stdout.splitlines() if line.startswith("FAILED")), flush=True)
            counts = dict((kind, int(n)) for n, kind in re.findall(r"(\d+) (passed|failed|error)", tail))
            failed += counts.get("failed", 0) + counts.get("error", 0)
            passed += counts.get("passed", 0)
    finally:
        for process in hogs:
            process.terminate()
    print(f"runs={args.runs} failed_runs={failed_runs} failed_tests={failed} tests={passed + failed} "
          f"mean_run_s={sum(seconds) / len(seconds):.0f} hogs={args.hogs}")  # fmt: skip
    return 0 if failed_runs == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
