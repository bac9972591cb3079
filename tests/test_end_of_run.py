"""What a person reads during and after `python -m lerobot_contrast.eval`: a header before the first trial, progress
with not-applicable trials counted, and a closing table of each perturbation's change paired against its bases."""

import contextlib
import io
import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from rich.console import Console

from lerobot_contrast.eval import main
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.reporting import analysis, stats
from lerobot_contrast.terminal.progress import RunProgress

SMALL = ["--n_instances=3", "--seed=5", "--policy.type=oracle", "--policy.noise_std=0.005", "--rerun=false"]


def run_eval(run: Path, *flags: str) -> list[str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main([*SMALL, f"--output_dir={run}", *flags]) == 0
    return out.getvalue().splitlines()


@pytest.fixture(scope="module")
def quiet(tmp_path_factory) -> tuple[Path, list[str]]:
    run = tmp_path_factory.mktemp("quiet") / "run"
    return run, run_eval(run)


def rows(lines: list[str]) -> dict[str, str]:
    return {line.split()[0]: line for line in lines if line.startswith(("original", "Δ", "all "))}


def test_the_table_shows_each_perturbations_change_paired_against_the_same_bases(quiet):
    run, lines = quiet
    results = stats.frame(pq.read_table(run / "results.parquet"))
    paired = stats.paired_sensitivity(results, "spl", analysis.rng())  # what `report` shows
    table = rows(lines)
    assert paired and table["original"].split()[1] == "3"
    for name, change in paired.items():
        assert f"{round(change.mean, 3) + 0.0:+.3f}" in table[f"Δ{name}"], (name, table)
    overall = stats.metric_estimate(results, "spl")
    assert f"{overall.mean:.3f} [{overall.low:.3f}, {overall.high:.3f}]" in table["all"]
    how = lines[lines.index(table["all"]) + 1]
    assert how.startswith("How to read: the change is paired (same base instances")


def test_a_header_comes_first_and_progress_counts_not_applicable_trials(quiet):
    run, lines = quiet
    assert lines[0].startswith("task language_table · policy oracle · strategy contrast")
    assert lines[1].startswith("plan: 21 planned trials") and lines[2] == f"run directory: {run}"
    assert f"--output_dir={run} --resume=true" in lines[3]
    assert not any("not applicable here" in line for line in lines)
    progress = [line for line in lines if line.startswith("trial ") and " not applicable · " in line]
    assert progress and all(line.endswith(" left") for line in progress)  # plain lines: stdout is not a terminal
    n_a = sum(r.status == "not_applicable" for r in read_journal(run / "journal.jsonl"))
    assert f"21/21 trials · {21 - n_a} ran, {n_a} not applicable · " in "\n".join(lines)


def test_verbose_keeps_a_line_per_trial_numbered_from_one(tmp_path):
    lines = run_eval(tmp_path / "run", "--verbose=true")
    trial_lines = [line for line in lines if line.startswith("[")]
    assert len(trial_lines) == 21 and trial_lines[0].startswith("[   1] original")
    assert trial_lines[-1].startswith("[  21]") and any("not applicable here" in line for line in trial_lines)


def test_on_a_terminal_the_progress_line_redraws_in_place(tmp_path):
    records = read_journal_of_a_small_run(tmp_path)
    screen = io.StringIO()
    console = Console(file=screen, force_terminal=True, width=120)
    with RunProgress(len(records), "m", console=console) as progress:
        for record in records:
            progress(record)
    drawn = screen.getvalue()
    assert "\x1b[" in drawn and "not applicable" in drawn  # rich redraws the bar with cursor moves
    assert f"{len(records)}/{len(records)} trials" in drawn
    plain = RunProgress(len(records), "m", console=Console(file=io.StringIO(), width=120), live=False)
    assert plain.bar is None and plain.plain_line().startswith(f"trial 0/{len(records)} · 0 ran")


def read_journal_of_a_small_run(tmp_path: Path) -> list:
    run_eval(tmp_path / "small")
    return read_journal(tmp_path / "small" / "journal.jsonl")


def test_a_stopping_rule_adds_its_anytime_valid_interval_under_the_all_row(tmp_path):
    run = tmp_path / "run"
    lines = run_eval(run, "--stop.width=0.99")
    stopping = json.loads((run / "summary.json").read_text())["stopping"]
    low, high = stopping["anytime_interval"]
    below_all = lines[lines.index(rows(lines)["all"]) + 1]
    assert below_all.strip() == f"[{low:.3f}, {high:.3f}] anytime-valid 95%, the stopping rule's"
