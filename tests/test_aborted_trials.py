"""Trials a lost robot aborted (issue 18, item 7): said as aborted on the console, counted in summary.json and the
table, and run again on resume unless --rerun_aborted=false keeps them."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from lerobot_contrast.contrast.cost import DistanceCost
from lerobot_contrast.contrast.strategy import make_plan
from lerobot_contrast.contrast.trial import Outcome
from lerobot_contrast.record.summary import format_summary
from lerobot_contrast.spine.evaluation import Evaluation, run
from lerobot_contrast.spine.runner import RobotLostError
from lerobot_contrast.terminal.lines import trial_line
from tests.contrast.test_strategy import bases, pusher
from tests.contrast.toy_task import ToyTask

TASK = ToyTask()
PLAN = make_plan("contrast", bases(2), TASK.perturbations.select(["LB", "SB"]), 1, np.random.default_rng(0))


def losing_at(index: int, ended_by: str = "disconnected"):
    """Runs trials as the pusher does until trial `index`, which the robot aborts; the next trial finds it gone."""
    push = pusher()

    def execute(context):
        if context.index > index:
            raise RobotLostError("the robot (toy) disconnected and could not reconnect")
        outcome = push(context)
        if context.index < index:
            return outcome
        extra = {"ended_by": ended_by}
        return Outcome(False, 0, 0.0, context.instance.scene, 0.1, status="aborted", extra=extra)

    return execute


def evaluation(run_dir, execute, **changes) -> Evaluation:
    return Evaluation(TASK, PLAN, DistanceCost(), execute=execute, output_dir=run_dir, config={"seed": 0}, **changes)


def lost_run(run_dir, index: int = 2, ended_by: str = "disconnected"):
    with pytest.raises(RobotLostError):
        run(evaluation(run_dir, losing_at(index, ended_by)))
    return journal(run_dir)


def journal(run_dir) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]


def summary(run_dir) -> dict:
    return json.loads((run_dir / "summary.json").read_text())


def test_an_aborted_trial_is_said_and_counted_as_aborted(tmp_path):
    records = lost_run(tmp_path / "run")
    assert [r["status"] for r in records] == ["done", "done", "aborted"]
    overall = summary(tmp_path / "run")["overall"]
    assert (overall["trials"], overall["aborted"], overall["not_applicable"], overall["skipped"]) == (2, 1, 0, 0)
    assert summary(tmp_path / "run")["per_perturbation"]["SB"]["aborted"] == 1
    table = format_summary(summary(tmp_path / "run"), "m").splitlines()
    assert table[0].split()[:5] == ["perturbation", "trials", "n/a", "aborted", "skipped"]
    assert table[-1].split()[:5] == ["all", "2", "0", "1", "0"]


def test_a_table_without_aborted_or_skipped_trials_leaves_their_columns_out(tmp_path):
    run(evaluation(tmp_path / "run", pusher()))
    table = format_summary(summary(tmp_path / "run"), "m").splitlines()
    assert table[0].split()[:4] == ["perturbation", "trials", "n/a", "success"]
    assert "aborted" not in table[0] and "skipped" not in table[0]


def test_the_console_says_aborted_and_skipped_apart_from_not_applicable(tmp_path):
    done = run(evaluation(None, pusher())).records[0]
    aborted = replace(done, status="aborted", steps=4, extra={"ended_by": "disconnected"})
    assert "aborted: the robot disconnected after 4 steps" in trial_line(aborted, "m")
    estop = replace(done, status="aborted", steps=2, extra={"ended_by": "estop"})
    assert "aborted: emergency stop after 2 steps" in trial_line(estop, "m")
    skipped = replace(done, status="skipped")
    assert trial_line(skipped, "m").endswith("skipped by the operator")
    assert "not applicable" not in trial_line(aborted, "m") + trial_line(skipped, "m")


def test_resume_runs_a_trial_the_lost_robot_aborted_again(tmp_path, capsys):
    run_dir = tmp_path / "run"
    lost_run(run_dir)
    uninterrupted = run(evaluation(tmp_path / "whole", pusher())).records
    results = run(evaluation(run_dir, pusher(), resume=True, verbose=True))
    out = capsys.readouterr().out
    assert "trial 2 was aborted when the robot disconnected; it runs again (--rerun_aborted=false keeps it)" in out
    assert [r["status"] for r in journal(run_dir)] == ["done"] * len(PLAN)
    same = ("index", "perturbation", "status", "success", "cost", "cumulative_cost")
    assert [[getattr(r, k) for k in same] for r in results.records] == [
        [getattr(r, k) for k in same] for r in uninterrupted
    ]
    assert summary(run_dir)["overall"]["aborted"] == 0 and summary(run_dir)["complete"] is True


def test_rerun_aborted_false_keeps_the_aborted_trial_and_goes_on_after_it(tmp_path):
    run_dir = tmp_path / "run"
    lost_run(run_dir)
    run(evaluation(run_dir, pusher(), resume=True, rerun_aborted=False))
    statuses = [r["status"] for r in journal(run_dir)]
    assert statuses == ["done", "done", "aborted"] + ["done"] * (len(PLAN) - 3)
    assert summary(run_dir)["overall"]["aborted"] == 1 and summary(run_dir)["complete"] is True


def test_an_emergency_stop_stays_aborted_on_resume(tmp_path):
    run_dir = tmp_path / "run"
    lost_run(run_dir, ended_by="estop")  # the operator's decision, not a fault: it is not run again
    run(evaluation(run_dir, pusher(), resume=True))
    assert [r["status"] for r in journal(run_dir)][:3] == ["done", "done", "aborted"]
