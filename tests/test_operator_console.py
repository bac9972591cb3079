"""The real-robot path on the simulated tabletop: prompts, scripted operator answers, labels, costs, resume."""

import io
import json
import sys
from pathlib import Path

import pytest

from lerobot_contrast.eval import main

# One base instance and two perturbations keep each session to a handful of prompts.
CONSOLE = ["--n_instances=1", "--seed=3", "--perturbations=[L,SB2]", "--operator=console", "--max_episode_steps=60"]


def journal(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def session(monkeypatch, run: Path, answers: list[str], *flags: str) -> int:
    monkeypatch.setattr(sys, "stdin", io.StringIO("".join(a + "\n" for a in answers)))
    return main([*CONSOLE, f"--output_dir={run}", *flags])


def test_the_console_prompts_what_to_move_and_records_each_label(tmp_path, monkeypatch, capsys):
    # Each trial: Enter once staged, then Enter to accept what the scene shows.
    assert session(monkeypatch, tmp_path / "run", [""] * 6) == 0
    out = capsys.readouterr().out
    assert "instruction:" in out and "move" in out and "planned cost" in out
    assert "leave as they are" in out
    records = [r for r in journal(tmp_path / "run") if r["status"] != "not_applicable"]
    assert records and all(r["status"] == "done" for r in records)
    assert all(r["extra"]["reset_s"] >= 0 for r in records)
    assert records[0]["success"] is True  # the oracle solves the base instance and the scene shows it


def test_an_operator_label_overrides_what_the_scene_shows(tmp_path, monkeypatch):
    assert session(monkeypatch, tmp_path / "run", ["", "n", "", "n", "", "n"]) == 0
    done = [r for r in journal(tmp_path / "run") if r["status"] == "done"]
    assert done and all(r["success"] is False for r in done)


def test_redo_repeats_the_trial_and_records_it_once(tmp_path, monkeypatch):
    assert session(monkeypatch, tmp_path / "run", ["", "r", "", "", "", "", "", ""]) == 0
    records = journal(tmp_path / "run")
    assert [r["index"] for r in records] == list(range(len(records)))
    assert records[0]["status"] == "done" and records[0]["success"] is True


def test_skip_records_a_skipped_trial_at_no_cost(tmp_path, monkeypatch):
    assert session(monkeypatch, tmp_path / "run", ["k", "", "", "", ""]) == 0
    first = journal(tmp_path / "run")[0]
    assert first["status"] == "skipped" and first["cost"] == 0.0 and first["cumulative_cost"] == 0.0


def test_a_corrected_distance_replaces_the_planned_cost(tmp_path, monkeypatch):
    assert session(monkeypatch, tmp_path / "run", ["c 0.5", "", "", "", "", ""]) == 0
    first = journal(tmp_path / "run")[0]
    assert first["cost"] == 0.5 and first["extra"]["moved_reported"] == 0.5


def test_reset_time_cost_is_the_measured_time_to_ready(tmp_path, monkeypatch):
    assert session(monkeypatch, tmp_path / "run", [""] * 6, "--cost=reset_time") == 0
    done = [r for r in journal(tmp_path / "run") if r["status"] == "done"]
    assert all(r["cost"] == pytest.approx(r["extra"]["reset_s"], abs=1e-3) for r in done)
    assert all(r["cost"] < 5.0 for r in done)  # scripted answers arrive at once, not the modelled seconds


def test_keys_end_a_trial_early_and_an_emergency_stop_aborts_it(tmp_path, monkeypatch):
    # Trial 0: the operator presses f at once. Trial 1: emergency stop, then Enter to go on.
    assert session(monkeypatch, tmp_path / "run", ["", "f", "", "e", "", "", ""]) == 0
    records = [r for r in journal(tmp_path / "run") if r["status"] != "not_applicable"]
    assert records[0]["success"] is False and records[0]["extra"]["ended_by"] == "failure"
    assert records[0]["steps"] == 0
    assert records[1]["status"] == "aborted" and records[1]["extra"]["ended_by"] == "estop"


def test_stop_keeps_every_label_and_resume_continues_where_it_stopped(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    assert session(monkeypatch, run, ["", "", "q"]) == 0
    said = f"; {len(journal(run))} trials recorded; continue with --output_dir={run} --resume=true\n"
    assert said in capsys.readouterr().out  # the single run's stop line counts what it kept
    assert [r["status"] for r in journal(run) if r["status"] != "not_applicable"] == ["done"]
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is False
    assert session(monkeypatch, run, [""] * 6, "--resume=true") == 0
    records = journal(run)
    assert [r["index"] for r in records] == list(range(len(records))) and len(records) > 1
    assert json.loads((run / "summary.json").read_text())["complete"] is True


def test_the_end_of_the_operators_input_stops_the_session_resumably(tmp_path, monkeypatch, capsys):
    assert session(monkeypatch, tmp_path / "run", [""]) == 0
    assert "input ended" in capsys.readouterr().out
    assert journal(tmp_path / "run") == []


def test_auto_needs_a_robot_that_reports_its_scene(tmp_path, monkeypatch, capsys):
    assert main(["--n_instances=1", "--operator=sometimes", f"--output_dir={tmp_path / 'run'}"]) == 2
    assert "--operator" in capsys.readouterr().err


def test_a_redo_lists_the_moves_from_where_the_first_attempt_left_things(tmp_path, monkeypatch, capsys):
    assert session(monkeypatch, tmp_path / "run", ["", "r", "", "", "", "", "", ""]) == 0
    shown = capsys.readouterr().out.split("trial 1/")
    first, redo = shown[1].split("planned cost")[0], shown[2].split("planned cost")[0]
    assert "move" in first and first != redo  # the oracle pushed a block: it is staged back from where it is now


def test_stopping_at_the_outcome_prompt_says_the_trial_is_not_recorded(tmp_path, monkeypatch, capsys):
    assert session(monkeypatch, tmp_path / "run", ["", "q"]) == 0
    out = " ".join(capsys.readouterr().out.split())  # rich wraps the prompt to the console's width
    assert "q stop (this trial is not recorded)" in out
    assert "before labelling trial 1, which is not recorded and runs again on resume" in out
    assert journal(tmp_path / "run") == []
