"""The pair directory: config.json (the session's settings), pairs.json (the policies and their run directories),
one normal run directory per policy, summary.json (the paired decisions and the restaging cost) and comparison.md.
This module owns pairs.json and the pair summary."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.record.run_dir import write_json_atomic

PAIRS_VERSION = 1
INDEX = "pairs.json"


class PairDirError(UserError):
    pass


def is_pair_dir(path: Path) -> bool:
    return (Path(path) / INDEX).is_file()


def write_index(path: Path, policies: Sequence[Mapping[str, Any]]) -> None:
    """`policies`: per policy, in --policies order, its `label`, run directory `name` and `policy` settings."""
    write_json_atomic(path / INDEX, {"version": PAIRS_VERSION, "policies": list(policies)})


def read_index(path: Path) -> list[dict[str, Any]]:
    try:
        index = json.loads((path / INDEX).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as error:
        raise PairDirError(f"{path / INDEX}: cannot read the interleaved run's index ({error})") from None
    if index.get("version") != PAIRS_VERSION:
        raise PairDirError(f"{path / INDEX}: version {index.get('version')!r}, this release reads {PAIRS_VERSION}")
    return index["policies"]


def policy_run_dirs(path: Path) -> list[Path]:
    """Each policy's run directory that has started (holds a config.json), in --policies order."""
    dirs = [Path(path) / entry["name"] for entry in read_index(Path(path))]
    return [d for d in dirs if (d / "config.json").is_file()]


def expand(specs: Sequence[str]) -> list[str]:
    """Report inputs with each pair directory replaced by its policies' run directories."""
    out: list[str] = []
    for spec in specs:
        out += [str(d) for d in policy_run_dirs(Path(spec))] if is_pair_dir(Path(spec)) else [spec]
    return out


def restaging_cost(records: Sequence[TrialRecord]) -> dict[str, float]:
    """The cost of staging each trial once (on the contrast chain) and of restaging it for the later policies."""
    staging = sum(r.cost for r in records if not r.extra.get("pairing", {}).get("restage"))
    restaging = sum(r.cost for r in records if r.extra.get("pairing", {}).get("restage"))
    total = staging + restaging
    return {"staging": staging, "restaging": restaging, "restage_share": restaging / total if total > 0 else 0.0}


def write_summary(path: Path, summary: Mapping[str, Any]) -> None:
    write_json_atomic(path / "summary.json", {"version": PAIRS_VERSION, **summary})


def pair_records(path: Path) -> list[TrialRecord]:
    """Every policy's journalled trials, policy after policy, each naming its Rerun file from the pair directory."""
    from lerobot_contrast.record.journal import read_journal

    out = []
    for entry in read_index(Path(path)):
        journal = Path(path) / entry["name"] / "journal.jsonl"
        for record in read_journal(journal) if journal.is_file() else []:
            rerun = None if record.rerun_path is None else f"{entry['name']}/{record.rerun_path}"
            out.append(dataclasses.replace(record, rerun_path=rerun))
    return out
