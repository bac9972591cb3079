"""Shared fixtures: a run recorded with both observers, and readers for what they wrote."""

from __future__ import annotations

import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

from lerobot_contrast.record.dataset import DatasetRecorder
from lerobot_contrast.record.rerun_log import RerunEpisodeRecorder
from tests.record.lt_episodes import Episodes, contexts, record_run

STEPS = 12  # long enough for the oracle to succeed in some trials and fail in others


@pytest.fixture(scope="session")
def recorded_run(tmp_path_factory) -> Path:
    """Two base instances, each with its ΔLB1 and ΔSB1 perturbation, recorded to Rerun and a LeRobotDataset."""
    run_dir = tmp_path_factory.mktemp("recorded") / "run"
    task = Episodes().task
    observers = [RerunEpisodeRecorder(run_dir, task=task), DatasetRecorder(run_dir, fps=10, robot_type="sim")]
    record_run(run_dir, contexts(n_bases=2), observers, steps=STEPS)
    return run_dir


def rerun_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rerun_cli", *args], capture_output=True, text=True, timeout=120)


def read_rrd(path: Path):
    """(store entries, {entity path: [chunks]}) through the pinned rerun-sdk's own reader."""
    from rerun.experimental import RrdReader

    reader = RrdReader(path)
    chunks = defaultdict(list)
    for chunk in reader.stream().to_chunks():
        chunks[chunk.entity_path].append(chunk)
    return reader, chunks


def static_row(chunks: list) -> dict:
    """The values of an entity's static row (properties, text documents), without Rerun's row ids."""
    (chunk,) = [c for c in chunks if c.is_static]
    row = chunk.to_record_batch().to_pylist()[0]
    return {
        k.split(":")[-1]: v[0] if isinstance(v, list) and len(v) == 1 else v for k, v in row.items() if "RowId" not in k
    }
