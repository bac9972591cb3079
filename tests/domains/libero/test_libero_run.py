"""A short contrast run on LIBERO through the evaluator's command line: a LeRobot ACT policy with random weights
(nothing downloaded) at 128x128, a few steps per trial, killed after its first trial and resumed."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("libero", reason="LIBERO is installed by the test set-up: bash scripts/setup.sh --libero")
pytestmark = pytest.mark.slow
ARGS = [
    "--task=libero_object", "--families=task0", "--n_instances=1", "--seed=0", "--strategy=contrast",
    "--perturbations=L,S,SB", "--policy.type=act", "--policy.device=cpu", "--max_episode_steps=4",
    "--robot.type=libero_sim", "--robot.observation_width=128", "--robot.observation_height=128",
]  # fmt: skip


def _journal(run: Path) -> list[dict]:
    path = run / "journal.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def test_a_random_act_policy_runs_a_libero_contrast_set_and_resumes_after_a_kill(tmp_path):
    run = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "lerobot_contrast.eval", *ARGS, f"--output_dir={run}"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    deadline = time.monotonic() + 900
    while time.monotonic() < deadline and not _journal(run) and proc.poll() is None:
        time.sleep(0.2)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    first = _journal(run)
    assert len(first) >= 1, proc.stderr.read()
    result = subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.eval", *ARGS, f"--output_dir={run}", "--resume=true"],
        capture_output=True, text=True, timeout=1200,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-2000:]
    records = _journal(run)
    assert records[: len(first)] == first  # nothing redone or lost
    assert [r["index"] for r in records] == list(range(len(records)))
    done = [r for r in records if r["status"] == "done"]
    assert done[0]["perturbation"] is None and 0 < done[0]["steps"] <= 4
    assert {r["perturbation"] for r in records} == {None, "L", "S", "SB"}
    moved = [r for r in done if r["perturbation"] in ("S", "SB")]
    assert moved and all(r["cost"] >= 0.05 for r in moved)  # a scene move carries one object 5-10 cm
    assert all(r["cost"] == 0.0 for r in done if r["perturbation"] == "L")
    assert all(r["rerun_path"] for r in done)  # a Rerun file per episode, both cameras
