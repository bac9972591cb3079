"""The run directory: config.json, journal.jsonl, results.parquet and summary.json, created or resumed safely."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.record.journal import Journal

# Settings that may differ between the original run and its resumption.
RESUME_FREE_KEYS = ("resume", "dry_run", "output_dir", "operator", "push_to_hub", "repo_id", "private")


class RunDirError(UserError):
    pass


@dataclass
class RunDir:
    path: Path
    journal: Journal

    @property
    def config_path(self) -> Path:
        return self.path / "config.json"

    @property
    def results_path(self) -> Path:
        return self.path / "results.parquet"

    @property
    def summary_path(self) -> Path:
        return self.path / "summary.json"

    def write_summary(self, summary: dict[str, Any]) -> None:
        write_json_atomic(self.summary_path, summary)


def write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def comparable_settings(config: dict[str, Any]) -> dict[str, Any]:
    """The settings two sessions of one run must share: all but where it is written, who operates it, where it
    is published and the robot's address."""
    comparable = {k: v for k, v in config.items() if k not in RESUME_FREE_KEYS}
    if isinstance(comparable.get("robot"), dict):  # the same robot may come back at a new address or port
        comparable["robot"] = {"type": comparable["robot"].get("type")}
    return comparable


def open_run_dir(path: Path, config: dict[str, Any], resume: bool) -> RunDir:
    """Create a new run directory, or reopen one with `resume`, refusing anything ambiguous."""
    config_path = path / "config.json"
    if resume:
        if not config_path.exists():
            raise RunDirError(f"--resume: {path} holds no run to resume (no config.json); drop --resume to start one")
        stored = json.loads(config_path.read_text(encoding="utf-8"))
        now, then = comparable_settings(config), comparable_settings(stored)
        changed = [
            f"--{k}={json.dumps(now[k])} (was {json.dumps(then.get(k))})" for k in sorted(now) if then.get(k) != now[k]
        ]
        if changed:
            raise RunDirError(
                f"--resume: {path} was started with other settings, {'; '.join(changed)}; drop those flags "
                "(a resumed run reads its settings from config.json) or choose a new --output_dir"
            )
    else:
        if path.exists() and any(path.iterdir()):
            raise RunDirError(
                f"--output_dir: {path} already exists; pass --resume=true to continue that run or choose a new directory"
            )
        try:
            path.mkdir(parents=True, exist_ok=True)
            write_json_atomic(config_path, config)
        except OSError as error:
            raise RunDirError(
                f"--output_dir: cannot write to {path} ({error.strerror}); choose a writable directory"
            ) from None
    return RunDir(path=path, journal=Journal.open(path / "journal.jsonl"))
