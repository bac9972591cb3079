"""The sweep folder: `sweep.json` naming its cells and their settings, one run directory per cell, and
`results.parquet` with every cell's trials. This module owns the sweep index and the sweep results table."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.record.results import read_results
from lerobot_contrast.record.run_dir import write_json_atomic

SWEEP_VERSION = 1
INDEX = "sweep.json"
RESULTS = "results.parquet"
# Columns the sweep table adds in front of each cell's trials.
CELL_COLUMNS = ("cell", "cell_status")


class SweepDirError(UserError):
    pass


def is_sweep_dir(path: Path) -> bool:
    return (path / INDEX).is_file()


def write_index(path: Path, cells: Sequence[Mapping[str, Any]]) -> None:
    """`cells`: one mapping per cell with at least its `name` (its run directory) and `settings`."""
    write_json_atomic(path / INDEX, {"version": SWEEP_VERSION, "cells": list(cells)})


def read_index(path: Path) -> list[dict[str, Any]]:
    try:
        index = json.loads((path / INDEX).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as error:
        raise SweepDirError(f"{path / INDEX}: cannot read the sweep index ({error})") from None
    if index.get("version") != SWEEP_VERSION:
        raise SweepDirError(
            f"{path / INDEX}: sweep index version {index.get('version')!r}, this release reads {SWEEP_VERSION}"
        )
    return index["cells"]


def cell_run_dirs(path: Path) -> list[Path]:
    """The run directories of the sweep's cells that have started (hold a config.json), in the index's order."""
    dirs = [path / cell["name"] for cell in read_index(path)]
    return [d for d in dirs if (d / "config.json").is_file()]


def is_complete(run_dir: Path) -> bool:
    summary = run_dir / "summary.json"
    try:
        return summary.is_file() and json.loads(summary.read_text(encoding="utf-8")).get("complete") is True
    except json.JSONDecodeError:
        return False


def write_sweep_results(path: Path, cells: Sequence[Mapping[str, Any]]) -> Path:
    """Every started cell's trials in one table, each row led by its cell's name, status and settings."""
    frames = []
    for cell in cells:
        results = path / cell["name"] / RESULTS
        if not results.is_file():
            continue
        trials = read_results(results).to_pandas()
        columns = {"cell": cell["name"], "cell_status": cell.get("status"), **_columns(cell["settings"])}
        for position, (name, value) in enumerate(columns.items()):
            # A setting named like a trial column (`cost: reset_time` beside each trial's cost) keeps both.
            trials.insert(position, f"cell_{name}" if name in trials else name, [value] * len(trials))
        frames.append(trials)
    table = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=list(CELL_COLUMNS))
    tmp = path / (RESULTS + ".tmp")
    table.to_parquet(tmp, index=False)
    os.replace(tmp, path / RESULTS)
    return path / RESULTS


def _columns(settings: Mapping[str, Any]) -> dict[str, Any]:
    """Settings as table cells: lists joined with '+', so every cell's column has one type."""
    return {
        key: "+".join(map(str, value)) if isinstance(value, list | tuple) else value for key, value in settings.items()
    }
