"""Shared result datasets end to end, against the fake Hub: a lab evaluates with Rerun and a LeRobotDataset and
publishes; another compares its own run with the published one, and re-runs the published plan on its policy."""

import json

import pyarrow.parquet as pq
from lerobot.datasets import LeRobotDataset

from lerobot_contrast.eval import main
from lerobot_contrast.report import main as report_main

REPO = "lab-a/lt-contrast-oracle"
FLAGS = ["--n_instances=2", "--seed=4", "--perturbations=[LB1,SB2]", "--max_episode_steps=40"]


def journal(run) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def test_publish_compare_and_rerun_a_published_plan(hub, tmp_path, monkeypatch):
    lab_a = tmp_path / "lab_a"
    assert (
        main([*FLAGS, "--record_dataset=true", "--push_to_hub=true", f"--repo_id={REPO}", f"--output_dir={lab_a}"]) == 0
    )
    done = [r for r in journal(lab_a) if r["status"] == "done"]
    assert all((lab_a / r["rerun_path"]).exists() for r in done)
    assert [r["dataset_episode"] for r in done] == list(range(len(done)))
    assert LeRobotDataset("local/lab_a", root=lab_a / "dataset").meta.total_episodes == len(done)
    published = hub.repo(REPO).head[1]
    assert {"results.parquet", "plan.json", "README.md", "dataset/meta/info.json"} <= set(published)
    assert any(path.startswith("rerun/episode_") for path in published)

    lab_b = tmp_path / "lab_b"
    assert main(["--plan=hub:" + REPO, "--policy.type=random", "--rerun=false", f"--output_dir={lab_b}"]) == 0
    planned = json.loads((lab_b / "plan.json").read_text())
    assert planned == json.loads((lab_a / "plan.json").read_text())
    assert json.loads((lab_b / "config.json").read_text())["seed"] == 4

    assert report_main([f"hub:{REPO}", str(lab_b)]) == 0  # written into the local run, not the Hub cache
    report = (lab_b / "report" / "report.md").read_text()
    assert "oracle" in report and "random" in report
    assert "## Policies on the same plan" in report  # lab B's --plan and recording flags do not change the design
    assert pq.read_table(lab_b / "results.parquet").num_rows == len(journal(lab_b))
    monkeypatch.chdir(tmp_path)
    assert report_main([f"hub:{REPO}"]) == 0
    assert (tmp_path / "report" / "report.md").exists()


def test_push_to_hub_needs_a_repo_id(tmp_path, capsys):
    assert main(["--n_instances=1", "--push_to_hub=true", f"--output_dir={tmp_path / 'run'}"]) == 2
    assert "--repo_id" in capsys.readouterr().err
