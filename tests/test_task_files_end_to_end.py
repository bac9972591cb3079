"""The shipped task files run end to end on the simulated LeRobot robot, with scripted operator answers."""

import io
import json
import sys

from lerobot_contrast.eval import main

SIM = ["--robot.type=language_table_sim", "--policy.type=random", "--n_instances=2", "--max_episode_steps=8"]


def run(monkeypatch, tmp_path, task: str, answers: list[str], *flags: str) -> list[dict]:
    monkeypatch.setattr(sys, "stdin", io.StringIO("".join(a + "\n" for a in answers)))
    out = tmp_path / task
    assert main([f"--task={task}", *SIM, f"--output_dir={out}", *flags]) == 0
    return [json.loads(line) for line in (out / "journal.jsonl").read_text().splitlines()]


def test_so101_blocks_is_staged_and_judged_on_the_simulated_tabletop(tmp_path, monkeypatch, capsys):
    # The cubes are simulator blocks: the console shows the plan, Enter accepts what the scene shows.
    records = run(monkeypatch, tmp_path, "so101_blocks", [""] * 40, "--operator=console")
    done = [r for r in records if r["status"] == "done"]
    assert len({r["base_id"] for r in done}) == 2 and any(r["perturbation"] for r in done)
    assert all(r["success"] is False for r in done)  # random pushes do not put a cube next to another
    assert all(r["cost"] >= 0 and "reset_s" in r["extra"] for r in done)
    assert "put the" in capsys.readouterr().out


def test_lekiwi_fetch_asks_the_operator_for_the_subgoals_reached(tmp_path, monkeypatch, capsys):
    # The room's objects are not simulator blocks, so the operator stages and labels every trial.
    records = run(monkeypatch, tmp_path, "lekiwi_fetch", ["", "1"] * 20)
    done = [r for r in records if r["status"] == "done"]
    assert done
    for record in done:
        n = len(record["instance"]["goal"]["subgoals"])
        assert record["progress"] == 1 / n and record["success"] is (n == 1)
    assert "subgoals reached" in capsys.readouterr().out


def test_the_dry_run_prices_the_plan_with_the_task_files_cost_model(capsys):
    assert main(["--task=lekiwi_fetch", "--cost=reset_time", "--n_instances=2", "--dry_run=true"]) == 0
    assert " s (assuming the robot leaves every scene as staged)" in capsys.readouterr().out
