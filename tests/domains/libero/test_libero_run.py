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

pytest.importorskip("libero", reason="LIBERO is installed by the test set-up: bash scripts/setup.sh --dev")
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
    _assert_charged_what_the_simulator_read_back(done)


def _assert_charged_what_the_simulator_read_back(done: list[dict]) -> None:
    """Each trial's cost is the distance from where the last trial left the objects (the first: beside the table)
    to where LIBERO reports them after settling, within 5 mm per object of the plan; the plan's is kept beside."""
    from lerobot_contrast import load_task
    from lerobot_contrast.contrast.scene import Pose, Scene

    task = load_task("libero_object", families=["task0"])
    cost_model, left = task.cost_model("distance"), task.storage_scene().to_json()["objects"]
    for record in done:
        staging = record["extra"]["staging"]
        before = Scene.from_json({"objects": staging["before"]})
        placed = Scene(objects={name: Pose(x, y) for name, (x, y) in staging["placed"].items()})
        planned = Scene.from_json(record["instance"]["scene"])
        assert staging["before"] == left  # from the scene the previous trial left behind
        assert abs(record["cost"] - cost_model(before, placed)) < 1e-4 * len(placed.objects)  # placed: to 0.1 mm
        assert abs(record["cost"] - staging["moved_m"]) < 1e-4
        assert all(placed.objects[n].distance_to(p) <= 0.005 for n, p in planned.objects.items())
        assert abs(record["cost"] - staging["planned_cost"]) <= 0.005 * len(planned.objects)
        left = record["scene_after"]["objects"]
    assert done[0]["cost"] > 0.5  # the first staging sets every object on the table
    assert all(r["rerun_path"] for r in done)  # a Rerun file per episode, both cameras
