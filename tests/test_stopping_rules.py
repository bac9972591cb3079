"""eval's stopping rules: a run stops after the trial that decides, says why, journals the sequential state per trial,
resumes exactly, and refuses bad rules and mismatched comparison runs in one line."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.trial import Outcome, TrialContext
from lerobot_contrast.eval import main, planned_evaluation
from lerobot_contrast.spine.config import EvalConfig, StopArgs
from lerobot_contrast.spine.evaluation import run


def succeeds(pattern):
    def execute(context: TrialContext) -> Outcome:
        return Outcome(
            success=pattern(context.index), steps=1, path_length=0.0, scene_after=context.instance.scene,
            duration_s=0.0,
        )  # fmt: skip

    return execute


def evaluate(output_dir: Path, stop: StopArgs, pattern, n_instances=40, resume=False, seed=3):
    planned = planned_evaluation(EvalConfig(n_instances=n_instances, seed=seed, stop=stop))
    evaluation = dataclasses.replace(
        planned,
        execute=succeeds(pattern),
        output_dir=output_dir,
        resume=resume,
        config={"seed": seed, "task": "language_table"},
    )
    return run(evaluation)


def journal(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]


def mostly(index: int) -> bool:
    return index % 5 != 0


def test_the_width_rule_stops_the_run_says_why_and_journals_each_state(tmp_path):
    results = evaluate(tmp_path / "run", StopArgs(width=0.6), mostly)
    stopping = results.summary["stopping"]
    assert stopping["reason"] == "width" and "at most 0.6 wide" in stopping["why"]
    low, high = stopping["anytime_interval"]
    assert high - low <= 0.6
    lines = journal(tmp_path / "run")
    assert len(lines) == len(results.records) < len(planned_evaluation(EvalConfig(n_instances=40, seed=3)).plan)
    assert lines[-1]["extra"]["sequential"]["stop"] == "width"
    assert all(line["extra"]["sequential"]["stop"] is None for line in lines[:-1])
    assert stopping["fixed_n_interval"][1] - stopping["fixed_n_interval"][0] < high - low


def test_a_resumed_run_continues_the_sequential_test_exactly(tmp_path):
    whole = evaluate(tmp_path / "whole", StopArgs(width=0.6), mostly)
    cut = len(whole.records) // 2

    def interrupted(index: int) -> bool:
        if index >= cut:  # the first trial from `cut` on that runs (some do not apply)
            raise KeyboardInterrupt
        return mostly(index)

    with pytest.raises(KeyboardInterrupt):
        evaluate(tmp_path / "cut", StopArgs(width=0.6), interrupted)
    assert cut <= len(journal(tmp_path / "cut")) < len(whole.records)
    resumed = evaluate(tmp_path / "cut", StopArgs(width=0.6), mostly, resume=True)
    strip = lambda lines: [(line["index"], line["success"], line["extra"]) for line in lines]  # noqa: E731
    assert strip(journal(tmp_path / "cut")) == strip(journal(tmp_path / "whole"))
    assert resumed.summary["stopping"] == whole.summary["stopping"]
    again = evaluate(tmp_path / "cut", StopArgs(width=0.6), mostly, resume=True)  # already decided: runs nothing
    assert len(again.records) == len(whole.records)


def test_a_comparison_stops_once_decided_and_names_the_better_policy(tmp_path):
    evaluate(tmp_path / "weak", StopArgs(), lambda index: False)
    results = evaluate(tmp_path / "strong", StopArgs(compare=str(tmp_path / "weak")), lambda index: True)
    stopping = results.summary["stopping"]
    assert (stopping["reason"], stopping["verdict"]) == ("decided", "better")
    assert stopping["difference_interval"][0] > 0 and stopping["compare"] == str(tmp_path / "weak")
    assert len(results.records) < len(journal(tmp_path / "weak"))


def test_a_comparison_run_with_another_plan_or_task_or_unfinished_is_refused_in_one_line(tmp_path):
    evaluate(tmp_path / "other", StopArgs(), mostly, seed=4)
    with pytest.raises(UserError, match=r"--stop.compare: trial 0 differs from .*'s plan"):
        planned_evaluation(EvalConfig(n_instances=40, seed=3, stop=StopArgs(compare=str(tmp_path / "other"))))
    summary = tmp_path / "other" / "summary.json"
    finished = summary.read_text()
    summary.write_text(json.dumps({**json.loads(finished), "complete": False}))
    with pytest.raises(UserError, match="--stop.compare: .* did not finish"):
        planned_evaluation(EvalConfig(n_instances=40, seed=4, stop=StopArgs(compare=str(tmp_path / "other"))))
    summary.write_text(finished)
    config = tmp_path / "other" / "config.json"
    config.write_text(json.dumps({**json.loads(config.read_text()), "task": "vln"}))
    with pytest.raises(UserError, match="--stop.compare: .* evaluated task 'vln', this run 'language_table'"):
        planned_evaluation(EvalConfig(n_instances=40, seed=4, stop=StopArgs(compare=str(tmp_path / "other"))))


@pytest.mark.parametrize("flag", ["--stop.width=0", "--stop.width=1.5", "--stop.alpha=1", "--stop.alpha=-0.05"])
def test_a_width_or_alpha_outside_zero_to_one_is_one_line(flag, capsys, tmp_path):
    assert main([flag, "--n_instances=2", f"--output_dir={tmp_path / 'run'}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and flag.split("=")[0] in err and "between 0 and 1" in err
    assert not (tmp_path / "run").exists()


def test_report_shows_the_anytime_valid_interval_beside_the_fixed_n_one(tmp_path):
    from lerobot_contrast.reporting import load_run
    from lerobot_contrast.reporting.build import build_report

    evaluate(tmp_path / "run", StopArgs(width=0.6), mostly)
    text = build_report([load_run(str(tmp_path / "run"))], tmp_path / "report").path.read_text()
    section = text.split("## Sequential stopping", 1)[1].split("\n## ", 1)[0]
    assert "| fixed-n interval | anytime-valid CS |" in section and "at most 0.6 wide" in section
    assert "valid only for a number of bases fixed in advance" in section


def test_the_console_shows_both_intervals_labelled_after_each_base(tmp_path, capsys):
    planned = planned_evaluation(EvalConfig(n_instances=40, seed=3, stop=StopArgs(width=0.6)))
    run(dataclasses.replace(planned, execute=succeeds(mostly), verbose=True))
    lines = [line.strip() for line in capsys.readouterr().out.splitlines() if "anytime-valid" in line]
    assert lines and all(line.startswith("progress: fixed-n 95% [") for line in lines)
    assert all("| anytime-valid 95% CS [" in line and line.endswith("bases)") for line in lines)
