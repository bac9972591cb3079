"""The twin's simulated clock against its wall clock, on the same unattended session (bench_unattended.py: the arm
stages, the camera labels, the demonstrator runs): the session once on the wall clock, then twice on the simulated
clock, idle and beside a CPU hog that keeps every core busy. Each session's journal is compared with the others.

    .venv/bin/python scripts/bench/bench_sim_clock.py [--bases=3] [--seed=0] [--work=DIR] [--hogs=N]

Prints each session's figures, then on its last line: wall_clock_s=... sim_clock_s=... speedup=... (this machine's
seconds for the evaluation's session on each clock, and their ratio) bench_speedup=... (the same for the whole
benchmark, the twin's start and the camera's calibration included) sim_hog_s=... sim_identical=... (the simulated clock's journals idle and
under load: the same statuses, labels, placements to the millimetre and robot seconds) wall_sim_agree=...
(the same statuses and labels on both clocks) wall_sim_placement_diff_cm=... (the largest difference in where a
trial's staging measured an object) late_frames=...
"""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from lerobot_contrast.spine.flags import ScriptParser

BENCH = Path(__file__).with_name("bench_unattended.py")
# What the wall clock puts in a journal and a simulated session cannot repeat: when a trial started, and a person's
# seconds (the scripted person's answers take the machine's time).
WALL_FIELDS = ("started_at", "reset_s", "person_s")
LATE = "did not reach the camera"  # what the simulated clock says of a frame LeRobot's camera did not get in time


def hog() -> None:
    while True:
        pass


def session(clock: str, work: Path, bases: int, seed: int) -> dict[str, str]:
    """Run the unattended benchmark on `clock` in `work` (a finished one is read back); its figures."""
    log = work / "bench.log"
    if not log.is_file() or "session_s=" not in log.read_text():
        command = [sys.executable, str(BENCH), f"--bases={bases}", f"--seed={seed}", f"--clock={clock}",
                   f"--work={work}"]  # fmt: skip
        done = subprocess.run(command, capture_output=True, text=True)
        work.mkdir(parents=True, exist_ok=True)
        log.write_text(done.stdout + done.stderr)
        if done.returncode != 0:
            raise SystemExit(f"error: the {clock} session failed (exit {done.returncode}); see {log}")
    last = log.read_text().strip().splitlines()[-1]
    print(f"{clock} ({work}): {last}", flush=True)
    return dict(pair.split("=", 1) for pair in last.split())


def canonical(value, digits: int = 4):
    """A journal record without its wall-clock fields, numbers rounded to `digits` (0.1 mm, 0.1 ms)."""
    if isinstance(value, dict):
        return {k: canonical(v, digits) for k, v in value.items() if k not in WALL_FIELDS}
    if isinstance(value, list):
        return [canonical(v, digits) for v in value]
    if isinstance(value, float):
        return round(value, digits)
    return value


def journal(work: Path) -> list[dict]:
    return [json.loads(line) for line in (work / "run" / "journal.jsonl").read_text().splitlines()]


def staged_diff_cm(first: list[dict], second: list[dict]) -> float:
    """The largest distance between where the two sessions' staging measured the same object of the same trial."""
    worst = 0.0
    for a, b in zip(first, second, strict=False):
        seen_a = a["extra"].get("staging", {}).get("placed", {})
        seen_b = b["extra"].get("staging", {}).get("placed", {})
        for name in seen_a.keys() & seen_b.keys():
            worst = max(worst, math.dist(seen_a[name], seen_b[name]) * 100)
    return worst


def main(argv: list[str] | None = None) -> int:
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bases", type=int, default=3, help="base instances of the contrast set")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--hogs", type=int, default=os.cpu_count() or 2, help="busy processes beside the third run")
    parser.add_argument("--work", type=Path, default=None, help="where the three sessions go; a finished one is kept")
    args = parser.parse_args(argv)
    if args.bases < 1 or args.hogs < 1:
        parser.error("--bases and --hogs must be at least 1")
    work = args.work or Path(tempfile.mkdtemp(prefix="bench_sim_clock_"))
    wall = session("wall", work / "wall", args.bases, args.seed)
    sim = session("sim", work / "sim", args.bases, args.seed)
    hogs = [multiprocessing.get_context("spawn").Process(target=hog, daemon=True) for _ in range(args.hogs)]
    for process in hogs:
        process.start()
    try:
        loaded = session("sim", work / "sim_hog", args.bases, args.seed)
    finally:
        for process in hogs:
            process.terminate()
    journals = {name: journal(work / name) for name in ("wall", "sim", "sim_hog")}
    identical = [canonical(r) for r in journals["sim"]] == [canonical(r) for r in journals["sim_hog"]]
    outcomes = {name: [(r["status"], r["success"]) for r in records] for name, records in journals.items()}
    late = sum(len(re.findall(LATE, (work / name / "bench.log").read_text())) for name in ("sim", "sim_hog"))
    wall_s, sim_s = float(wall["session_s"]), float(sim["session_s"])
    bench_ratio = float(wall["wall_s"]) / float(sim["wall_s"])
    print(f"wall_clock_s={wall_s:.0f} sim_clock_s={sim_s:.0f} speedup={wall_s / sim_s:.2f} "
          f"bench_speedup={bench_ratio:.2f} sim_hog_s={loaded["session_s"]} "
          f"sim_identical={str(identical).lower()} wall_sim_agree={str(outcomes['wall'] == outcomes['sim']).lower()} "
          f"wall_sim_placement_diff_cm={staged_diff_cm(journals['wall'], journals['sim']):.2f} late_frames={late}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
