"""`--stop.compare=RUN_DIR|hub:USER/NAME`: the finished run a sequential comparison pairs this run's trials with.

Pairing needs the same plan (trial by trial), the same task and the same headline metric; anything else is refused
in one line naming the difference.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.stopping import StopError, StopRule, headline_metric, reference_values
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.record.plan_file import PLAN_FILE, plan_json


def compare_rule(source: str, plan: list[PlannedTrial], task: str, width: float | None, alpha: float) -> StopRule:
    """The stop rule comparing against the run `source` names (downloaded first for hub:USER/NAME)."""
    from lerobot_contrast.record.hub import resolve_run

    path = resolve_run(source)
    if not (path / "config.json").is_file() or not (path / "journal.jsonl").is_file():
        raise StopError(f"--stop.compare: {source} holds no finished run (config.json and journal.jsonl)")
    theirs = _read(path / "config.json", source)
    if theirs.get("task") != task:
        raise StopError(f"--stop.compare: {source} evaluated task {theirs.get('task')!r}, this run {task!r}")
    _check_plan(path, source, plan)
    summary = _read(path / "summary.json", source) if (path / "summary.json").is_file() else {}
    if not summary.get("complete", False):
        raise StopError(
            f"--stop.compare: {source} did not finish (its summary.json is missing or incomplete); resume it first"
        )
    records = read_journal(path / "journal.jsonl")
    metric = headline_metric(records)
    return StopRule(width, alpha, reference_values(records, metric), source, metric)


def _read(path: Path, source: str) -> dict[str, Any]:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        raise StopError(f"--stop.compare: {path} of {source} is not readable JSON") from None


def _check_plan(path: Path, source: str, plan: list[PlannedTrial]) -> None:
    if not (path / PLAN_FILE).is_file():
        raise StopError(f"--stop.compare: {source} has no {PLAN_FILE}, so its plan cannot be matched")
    theirs = _read(path / PLAN_FILE, source).get("trials", [])
    ours = json.loads(json.dumps(plan_json(plan)["trials"]))
    if len(theirs) != len(ours):
        raise StopError(
            f"--stop.compare: {source} planned {len(theirs)} trials, this run {len(ours)}; "
            "run with its --plan so both follow the same plan"
        )
    for a, b in zip(ours, theirs, strict=True):
        if a != b:
            field = next((k for k in a if a[k] != b.get(k)), "base")
            raise StopError(
                f"--stop.compare: trial {a['index']} differs from {source}'s plan in {field!r}; "
                "run with its --plan so both follow the same plan"
            )
