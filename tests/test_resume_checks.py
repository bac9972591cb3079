"""A resumed run checks its journal against its plan (plan.json) and settings (config.json) before it runs a
trial: anything but a torn last line is refused in one line that names the file, and the run is left as it was."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.eval import planned_evaluation
from lerobot_contrast.spine.config import EvalConfig
from lerobot_contrast.spine.evaluation import assume_unchanged, run


def evaluate(output_dir: Path, seed: int = 3, resume: bool = False, **settings):
    planned = planned_evaluation(EvalConfig(n_instances=3, seed=seed, **settings))
    config = {"seed": seed, **settings}
    evaluation = dataclasses.replace(
        planned, execute=assume_unchanged, output_dir=output_dir, resume=resume, config=config, verbose=True
    )
    return run(evaluation)


def lines(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


def contents(run_dir: Path) -> dict[str, bytes]:
    """Every file of the run but its lock, which each writer stamps with its process."""
    files = (p for p in sorted(run_dir.rglob("*")) if p.is_file() and p.name != ".lock")
    return {p.relative_to(run_dir).as_posix(): p.read_bytes() for p in files}


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    run_dir = tmp_path_factory.mktemp("finished") / "run"
    evaluate(run_dir)
    return run_dir


@pytest.fixture(scope="module")
def other_run(tmp_path_factory) -> Path:
    run_dir = tmp_path_factory.mktemp("other") / "run"
    evaluate(run_dir, seed=4)
    return run_dir


def duplicate_line(run_dir, other):
    journal = run_dir / "journal.jsonl"
    kept = lines(journal)
    journal.write_text("".join(kept[:3] + kept[2:]))


def delete_middle_line(run_dir, other):
    journal = run_dir / "journal.jsonl"
    kept = lines(journal)
    journal.write_text("".join(kept[:2] + kept[3:]))


def line_beyond_the_plan(run_dir, other):
    journal = run_dir / "journal.jsonl"
    last = json.loads(lines(journal)[-1])
    journal.write_text(journal.read_text() + json.dumps({**last, "index": last["index"] + 1}) + "\n")


def another_runs_journal(run_dir, other):
    shutil.copyfile(other / "journal.jsonl", run_dir / "journal.jsonl")


def edited_plan(run_dir, other):
    shutil.copyfile(other / "plan.json", run_dir / "plan.json")


def journal_is_a_directory(run_dir, other):
    (run_dir / "journal.jsonl").unlink()
    (run_dir / "journal.jsonl").mkdir()


def config_is_a_directory(run_dir, other):
    (run_dir / "config.json").unlink()
    (run_dir / "config.json").mkdir()


def config_is_not_json(run_dir, other):
    (run_dir / "config.json").write_text('{"seed": 3')


MALFORMED = {
    "a duplicated line": (duplicate_line, r"journal.jsonl: line 4 holds trial 2, expected trial 3"),
    "a deleted middle line": (delete_middle_line, r"journal.jsonl: line 3 holds trial 3, expected trial 2"),
    "a line beyond the plan": (line_beyond_the_plan, r"journal.jsonl: \d+ lines, beyond the plan's \d+ trials"),
    "another run's journal": (another_runs_journal, r"journal.jsonl: line 1 is not trial 0 of this run's plan"),
    "an edited plan.json": (edited_plan, r"plan.json is not the plan config.json's settings give"),
    "journal.jsonl a directory": (journal_is_a_directory, r"journal.jsonl: cannot read the journal \(Is a directory"),
    "config.json a directory": (config_is_a_directory, r"cannot read .*config.json \(Is a directory\)"),
    "config.json not JSON": (config_is_not_json, r"config.json is not valid JSON"),
}


@pytest.mark.parametrize("case", MALFORMED)
def test_a_journal_or_run_file_that_does_not_match_the_plan_is_refused_and_left_as_it_was(
    tmp_path, finished, other_run, case
):
    damage, message = MALFORMED[case]
    run_dir = tmp_path / "run"
    shutil.copytree(finished, run_dir)
    damage(run_dir, other_run)
    before = contents(run_dir)
    with pytest.raises(UserError, match=message) as refused:
        evaluate(run_dir, resume=True)
    assert "\n" not in str(refused.value)
    assert contents(run_dir) == before


def test_a_torn_last_line_is_repaired_said_and_its_trial_run_again(tmp_path, finished, capsys):
    run_dir = tmp_path / "run"
    shutil.copytree(finished, run_dir)
    journal = run_dir / "journal.jsonl"
    kept = lines(journal)
    journal.write_text("".join(kept[:-1]) + kept[-1][:40])
    evaluate(run_dir, resume=True)
    assert (
        f"{journal}: dropped its last line, cut off mid-write by a kill; that trial runs again"
        in capsys.readouterr().out
    )
    resumed, original = [json.loads(line) for line in lines(journal)], [json.loads(line) for line in kept]
    assert [r["instance"] for r in resumed] == [r["instance"] for r in original]
    assert [r["index"] for r in resumed] == list(range(len(original)))


def test_a_journal_past_the_budget_is_refused(tmp_path, finished):
    run_dir = tmp_path / "run"
    shutil.copytree(finished, run_dir)
    with pytest.raises(UserError, match="other settings"):  # a changed budget is refused as a changed setting
        evaluate(run_dir, resume=True, budget=5.0)
    config = json.loads((run_dir / "config.json").read_text())
    (run_dir / "config.json").write_text(json.dumps({**config, "budget": 5.0}))
    with pytest.raises(UserError, match=r"journal.jsonl: \d+ lines, beyond the budget's \d+ trials from line"):
        evaluate(run_dir, resume=True, budget=5.0)
