"""The results table (`results.parquet`): one row per journal record. This module owns its schema."""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from lerobot_contrast.contrast.trial import TrialRecord

RESULTS_VERSION = 2

SCHEMA = pa.schema(
    [
        ("index", pa.int64()),
        ("base_id", pa.string()),
        ("instance_id", pa.string()),
        ("family", pa.string()),
        ("perturbation", pa.string()),
        ("axis", pa.string()),
        ("staging", pa.string()),
        ("repeat", pa.int64()),
        ("status", pa.string()),
        ("instruction", pa.string()),
        ("cost", pa.float64()),
        ("cumulative_cost", pa.float64()),
        ("success", pa.bool_()),
        ("spl", pa.float64()),
        ("progress", pa.float64()),
        ("path_length", pa.float64()),
        ("reference_length", pa.float64()),
        ("steps", pa.int64()),
        ("duration_s", pa.float64()),
        ("started_at", pa.string()),
        ("rerun_path", pa.string()),
        ("dataset_episode", pa.int64()),
        ("extra", pa.string()),  # JSON: how the episode ended, the operator's reset time, task-specific metrics
    ]
)


def record_row(record: TrialRecord) -> dict[str, Any]:
    row = {name: getattr(record, name, None) for name in SCHEMA.names}
    row["instance_id"] = record.instance_id
    row["instruction"] = None if record.instance is None else record.instance.instruction
    row["extra"] = json.dumps(dict(record.extra), sort_keys=True)
    return row


def write_results(path: Path, records: Iterable[TrialRecord], metadata: dict[str, str]) -> None:
    """Write the table atomically, so a reader never sees a half-written file."""
    rows = [record_row(r) for r in records]
    table = pa.Table.from_pylist(rows, schema=SCHEMA)
    meta = {"lerobot_contrast.results_version": str(RESULTS_VERSION), **metadata}
    table = table.replace_schema_metadata({k.encode(): v.encode() for k, v in meta.items()})
    tmp = path.with_suffix(".parquet.tmp")
    try:
        pq.write_table(table, tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def read_results(path: Path) -> pa.Table:
    table = pq.read_table(path)
    version = (table.schema.metadata or {}).get(b"lerobot_contrast.results_version", b"?").decode()
    if version != str(RESULTS_VERSION):
        raise ValueError(f"{path}: results version {version}, this release reads {RESULTS_VERSION}")
    return table
