"""`plan.json`: the planned trials of a run (base instances in full, perturbation names, staging, repeats).

This module owns its format. Another lab re-runs the same contrast set from it with `eval --plan`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.record.run_dir import write_json_atomic

PLAN_VERSION = 1
PLAN_FILE = "plan.json"
# The settings that decide a plan: `eval --plan` takes them from the published run.
PLAN_SETTINGS = (
    "task", "families", "strategy", "perturbations", "order", "n_instances", "repeats", "seed", "cost", "budget",
    "max_episode_steps",
)  # fmt: skip


def plan_json(plan: list[PlannedTrial]) -> dict[str, Any]:
    return {"version": PLAN_VERSION, "trials": [{**t.to_json(), "base": t.base.to_json()} for t in plan]}


def write_plan(run_dir: Path, plan: list[PlannedTrial]) -> None:
    write_json_atomic(run_dir / PLAN_FILE, plan_json(plan))


def keep_plan(run_dir: Path, plan: list[PlannedTrial]) -> None:
    """Write the plan of a run, or, where the run has written it already, refuse a plan that differs from it."""
    path = run_dir / PLAN_FILE
    if not path.exists():
        write_plan(run_dir, plan)
        return
    todo = "restore config.json and plan.json as the run wrote them, or install the release the run was made with"
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        raise UserError(f"--resume: {path} is not readable JSON; {todo}") from None
    if stored != json.loads(json.dumps(plan_json(plan))):
        raise UserError(
            f"--resume: {path} is not the plan config.json's settings give (one of them was edited, or this "
            f"release plans differently); {todo}"
        )


def check_same_plan(source: Path, plan: list[PlannedTrial]) -> None:
    """Refuse to run when this release rebuilds a different plan from the published settings."""
    path = source / PLAN_FILE
    if not path.exists():
        return
    published = json.loads(path.read_text(encoding="utf-8"))
    if published.get("version") != PLAN_VERSION:
        raise UserError(f"--plan: {path} has plan version {published.get('version')!r}, this release reads 1")
    if published["trials"] != json.loads(json.dumps(plan_json(plan)["trials"])):
        raise UserError(
            f"--plan: this release builds a different plan from {source}'s settings than the one it published "
            "(a different version of the task); install the version the run was made with"
        )
