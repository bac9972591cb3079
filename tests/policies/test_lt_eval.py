"""A converted checkpoint in the released format is evaluated by `python -m lerobot_contrast.eval --policy.path`."""

import json
import subprocess
import sys


def test_the_converted_policy_runs_a_contrast_evaluation_in_the_simulator(converted, tmp_path):
    run = tmp_path / "run"
    flags = ["--n_instances=1", "--seed=2", "--perturbations=[L,LB1]", "--max_episode_steps=6"]
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "lerobot_contrast.eval",
            f"--policy.path={converted}",
            "--policy.device=cpu",
            *flags,
            f"--output_dir={run}",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    records = [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
    done = [r for r in records if r["status"] == "done"]
    assert done and all(r["steps"] == 6 for r in done if not r["success"])
    assert json.loads((run / "summary.json").read_text())["settings"]["policy"] == str(converted)
