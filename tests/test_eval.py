"""End to end: `python -m lerobot_contrast.eval` in the simulator, kill-and-resume, and bad-input messages."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from lerobot_contrast.eval import main

SMALL = ["--n_instances=3", "--seed=5", "--policy.type=oracle", "--policy.noise_std=0.005"]
# Long enough (35 planned trials, a dozen that run) that a signal sent after the fourth trial lands mid-run.
LONGER = ["--n_instances=5", "--seed=5", "--policy.type=oracle", "--policy.noise_std=0.005"]
TIMING = ("duration_s", "started_at")


def journal(run: Path) -> list[dict]:
    lines = (run / "journal.jsonl").read_text().splitlines()
    return [{k: v for k, v in json.loads(line).items() if k not in TIMING} for line in lines]


def test_a_contrast_run_writes_a_complete_run_directory(tmp_path, capsys):
    run = tmp_path / "run"
    assert main([*SMALL, f"--output_dir={run}"]) == 0
    records = journal(run)
    assert [r["index"] for r in records] == list(range(len(records)))
    assert {r["perturbation"] for r in records} == {None, "L", "LB1", "LB2", "S", "SB1", "SB2"}
    table = pq.read_table(run / "results.parquet")
    assert table.num_rows == len(records)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is True and summary["overall"]["trials"] == sum(r["status"] == "done" for r in records)
    assert summary["per_perturbation"]["original"]["trials"] == 3
    assert json.loads((run / "config.json").read_text())["strategy"] == "contrast"
    out = capsys.readouterr().out
    assert "ΔLB2" in out and "success" in out
    done = [r for r in records if r["status"] == "done"]
    assert all(0.0 <= r["spl"] <= 1.0 and r["reference_length"] > 0 for r in done)
    assert all(r["cost"] == 0.0 for r in done if r["axis"] in ("L", "LB"))


def test_a_killed_run_resumes_without_losing_or_repeating_a_trial(tmp_path, capsys):
    reference, killed = tmp_path / "reference", tmp_path / "killed"
    assert main([*LONGER, f"--output_dir={reference}"]) == 0
    proc = start_and_wait(killed, 4)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    partial = len(journal(killed))
    assert 4 <= partial < len(journal(reference))
    capsys.readouterr()
    # The resume in this process: what it reads is the killed process's files, and another interpreter loading
    # torch and LeRobot again would only add seconds.
    assert main([*LONGER, f"--output_dir={killed}", "--resume=true"]) == 0
    assert f"resuming {killed} at trial {partial + 1}" in capsys.readouterr().out  # numbered from 1, as every line is
    assert journal(killed) == journal(reference)


def start_and_wait(run: Path, lines: int) -> subprocess.Popen:
    proc = subprocess.Popen(
        [sys.executable, "-m", "lerobot_contrast.eval", *LONGER, f"--output_dir={run}"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        path = run / "journal.jsonl"
        if path.exists() and path.read_text().count("\n") >= lines:
            break
        time.sleep(0.01)
    return proc


def test_ctrl_c_keeps_every_finished_trial_and_marks_the_summary_incomplete(tmp_path, capsys):
    run = tmp_path / "run"
    proc = start_and_wait(run, 4)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert f"--output_dir={run} --resume=true" in stderr
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is False
    assert pq.read_table(run / "results.parquet").num_rows == len(journal(run)) >= 4
    hint = stderr.split("continue with ")[-1].split()
    assert main(hint) == 0  # the run's own config.json supplies every other setting (in this process, as above)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is True and len(journal(run)) == summary["settings"]["planned_trials"]
    capsys.readouterr()
    assert main([*hint, "--seed=6"]) == 2
    assert "--seed=6 (was 5); drop those flags" in capsys.readouterr().err


def test_the_same_seed_gives_the_same_results(tmp_path):
    assert main([*SMALL, "--strategy=standard", f"--output_dir={tmp_path / 'a'}"]) == 0
    assert main([*SMALL, "--strategy=standard", f"--output_dir={tmp_path / 'b'}"]) == 0
    assert journal(tmp_path / "a") == journal(tmp_path / "b")


def test_dry_run_prints_the_staging_and_writes_nothing(tmp_path, capsys):
    assert main(["--n_instances=2", "--dry_run=true", f"--output_dir={tmp_path / 'run'}"]) == 0
    out = capsys.readouterr().out
    assert "move red_moon" in out or "move " in out
    assert "planned cost" in out
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--perturbations=[LB9]"],
            "--perturbations: unknown perturbation 'LB9' for task 'language_table'; choose from: L, LB1",
        ),
        (["--budget=0.01"], "--budget 0.01 m is below the cost of staging the first trial"),
        (["--strategy=iid"], "--strategy: unknown strategy 'iid'"),
        (["--n_instance=3"], "unknown flag --n_instance"),
        (["--budget=lots"], "--budget: couldn't parse 'lots' into a float; see --help"),
        (["--rename_map=top"], "--rename_map: could not read 'top' as dict[str, str]; see --help"),
        (["--robot.type=language_table_sim", "--robot.camera=maybe"], "--robot.camera: couldn't parse 'maybe'"),
        (["--resume=true"], "--resume needs --output_dir"),
        (["--families=[block2nowhere]"], "--families: unknown Language-Table families ['block2nowhere']"),
        (["--seed"], "--seed needs a value, e.g. --seed=VALUE or --seed VALUE"),
        (["--robot.type=so102_follower"], "--robot.type=so102_follower is not a known robot; known: bi_openarm"),
    ],
)
def test_bad_input_gets_one_line_naming_the_flag(args, message, capsys):
    assert main([*args, "--dry_run=true"]) == 2
    stderr = capsys.readouterr().err
    assert stderr.count("\n") == 1 and message in stderr, stderr


def test_a_list_flag_takes_a_bare_comma_list_as_well_as_brackets(capsys):
    plans = []
    for value in ("LB1,SB2", "[LB1,SB2]"):
        assert main(["--n_instances=2", f"--perturbations={value}", "--dry_run=true"]) == 0
        plans.append(capsys.readouterr().out)
    assert plans[0] == plans[1]
    assert "ΔSB2" in plans[0] and "ΔLB2" not in plans[0]


def test_lerobots_own_robots_are_known_and_an_unbuildable_one_leaves_nothing_behind(tmp_path, capsys):
    arm = ["--task=so101_blocks", "--robot.type=so101_follower", "--robot.port=/dev/ttyNONE", "--robot.id=arm"]
    assert main([*arm, "--dry_run=true"]) == 0
    assert "plan: " in capsys.readouterr().out
    run = tmp_path / "run"
    assert main([*arm, f"--output_dir={run}"]) == 2
    stderr = capsys.readouterr().err
    assert stderr.count("\n") == 1 and "--robot.type=so1" in stderr, stderr
    assert not run.exists()


def test_an_existing_run_directory_needs_resume_and_an_unwritable_one_is_named(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.json").write_text("{}")
    assert main(["--n_instances=1", f"--output_dir={run}"]) == 2
    assert "already exists; pass --resume=true" in capsys.readouterr().err
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["--n_instances=1", f"--output_dir={blocker / 'run'}"]) == 2
    stderr = capsys.readouterr().err
    assert "--output_dir: cannot write to" in stderr and stderr.count("\n") == 1


def test_the_run_stops_after_the_trial_that_exceeds_the_budget(tmp_path, capsys):
    run = tmp_path / "run"
    assert main([*SMALL, "--budget=4", f"--output_dir={run}"]) == 0
    records = [r for r in journal(run) if r["status"] == "done"]
    assert records[-1]["cumulative_cost"] > 4 and all(r["cumulative_cost"] <= 4 for r in records[:-1])
    assert "stopped at the budget" in capsys.readouterr().out


def test_a_run_started_before_a_setting_existed_resumes_with_that_setting_at_its_default(tmp_path, capsys):
    run = tmp_path / "run"
    assert main([*SMALL, "--budget=5", f"--output_dir={run}"]) == 0
    config = json.loads((run / "config.json").read_text())
    del config["stop"], config["policy"]["language_blind"]  # as an older release wrote it
    (run / "config.json").write_text(json.dumps(config))
    before = len(journal(run))
    assert main([*SMALL, "--budget=6", f"--output_dir={run}", "--resume=true"]) == 2  # a changed setting still is
    assert "--budget=6.0 (was 5.0)" in capsys.readouterr().err
    assert main([f"--output_dir={run}", "--resume=true"]) == 0
    assert main([f"--output_dir={run}", "--resume=true", "--stop.width=0.5"]) == 2
    assert "--stop=" in capsys.readouterr().err and len(journal(run)) == before


def test_an_added_object_is_listed_with_what_bringing_it_in_is_charged(capsys):
    assert main(["--task=so101_blocks", "--robot.type=so101_follower", "--robot.port=/dev/null", "--dry_run=true"]) == 0
    moves = [line for line in capsys.readouterr().out.splitlines() if "(off the table)" in line]
    assert moves and all(line.endswith(", charged 0.21 m") for line in moves), moves  # from the tray
    assert any("(off the table) -> (" in line and "brought in" in line for line in moves)


def test_a_robot_without_its_motor_extra_is_named_as_given(tmp_path, capsys, monkeypatch):
    from lerobot.utils import import_utils

    # Where LeRobot's driver asks whether the feetech extra is installed (the twin's set-up installs it): it is not.
    monkeypatch.setitem(import_utils._require_package_cache, "scservo_sdk", False)
    args = ["--task=so101_blocks", "--robot.type=so101_follower", "--robot.port=/dev/null", "--n_instances=1"]
    assert main([*args, f"--output_dir={tmp_path / 'run'}"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --robot.type=so101_follower: cannot build the robot") and "feetech" in err
    assert not (tmp_path / "run").exists()


def test_an_existing_run_directory_is_refused_before_the_policy_loads(tmp_path, monkeypatch, capsys):
    import lerobot_contrast.eval as command

    def must_not_load(*args, **kwargs):
        raise AssertionError("the policy loaded before the run directory was checked")

    monkeypatch.setattr(command, "make_policy", must_not_load)
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "journal.jsonl").write_text("")
    assert main(["--n_instances=1", f"--output_dir={tmp_path / 'run'}"]) == 2
    assert "already exists; pass --resume=true" in capsys.readouterr().err


def test_a_dry_run_names_a_policy_path_that_is_not_there(tmp_path, capsys):
    assert main([f"--policy.path={tmp_path / 'no_such_model'}", "--dry_run=true"]) == 2
    assert capsys.readouterr().err == (
        f"error: --policy.path: no such directory: {tmp_path / 'no_such_model'}; give a directory written by "
        "save_pretrained or a Hub repo id\n"
    )
