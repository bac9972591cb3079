"""What the page shows, as one JSON document: the runs, read as `report` reads them, their trials and pairs, the
report's tables, and the A/B sessions among them; rebuilt only when a run's files change (a run in progress)."""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lerobot_contrast.record.audit_labels import AUDIT_FILE, read_labels
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.reporting.analysis import primary_metric
from lerobot_contrast.reporting.markdown import used_settings
from lerobot_contrast.reporting.runs import Run, load_run, policy_label, policy_pairs, strategy_label
from lerobot_contrast.view import numbers, trials
from lerobot_contrast.view.episodes import Dataset

# The files whose change means the page is out of date.
WATCHED = ("journal.jsonl", "summary.json", "results.parquet", "config.json", "dataset/meta/info.json", AUDIT_FILE)


@dataclass
class Inputs:
    """The runs a page is about, as `report` takes them (pair directories expanded, repeats counted once)."""

    specs: list[str]
    pair_dirs: list[Path]
    runs: list[Run]
    notes: list[str]


def load_inputs(specs: list[str]) -> Inputs:
    from lerobot_contrast.pairing.pair_dir import expand, is_pair_dir
    from lerobot_contrast.reporting.runs import distinct_runs, run_specs

    pair_dirs = [Path(spec) for spec in specs if is_pair_dir(Path(spec))]
    expanded = run_specs(expand(specs))
    runs, notes = distinct_runs(expanded, [load_run(spec) for spec in expanded])
    return Inputs(specs, pair_dirs, runs, notes)


def stamp(inputs: Inputs) -> str:
    """Changes whenever a watched file of any input changes (size or modification time)."""
    parts = []
    for folder in [run.path for run in inputs.runs] + inputs.pair_dirs:
        for name in (*WATCHED, "pairs.json"):
            path = folder / name
            if path.is_file():
                status = path.stat()
                parts.append(f"{path}:{status.st_size}:{status.st_mtime_ns}")
    return str(hash("|".join(parts)) & 0xFFFFFFFFFFFF)


def run_json(run_id: str, run: Run, metric: str) -> dict[str, Any]:
    journal = run.path / "journal.jsonl"
    records = read_journal(journal) if journal.is_file() else []
    dataset = Dataset(run.path)
    later = read_labels(run.path)
    return {
        "id": run_id,
        "name": run.name,
        "path": str(run.path),
        "complete": run.complete,
        "policy": policy_label(run.config),
        "strategy": strategy_label(run),
        "cost_unit": run.cost_unit,
        "video_base": f"videos/{run_id}/",  # where the page finds the dataset's video files
        "settings": {k: v for k, v in used_settings(run.config).items()},
        "trials": [trials.trial_json(r, later.get(r.index)) for r in records],
        "pairs": trials.pairs(records),
        "curves": trials.curves(run, metric),
        "videos_absent": dataset.absent_why(run.config),
        "journal_absent": None if records else "this run has no journal.jsonl, so its scenes and pairs are absent",
    }


def sessions_json(pair_dirs: list[Path], ids: dict[Path, str]) -> list[dict[str, Any]]:
    """Each A/B session (pair directory): its policies' runs, the sequential test's verdicts and the cost."""
    from lerobot_contrast.pairing.pair_dir import read_index

    out = []
    for path in pair_dirs:
        summary_path = path / "summary.json"
        summary = json.loads(summary_path.read_text(encoding="utf-8")) if summary_path.is_file() else {}
        policies = [{"label": e["label"], "run": ids.get((path / e["name"]).resolve())} for e in read_index(path) if e]
        out.append({"name": path.name, "policies": policies, "stopping": summary.get("stopping"),
                    "cost": summary.get("cost"), "cost_unit": summary.get("cost_unit")})  # fmt: skip
    return out


def build(inputs: Inputs, live: bool) -> dict[str, Any]:
    runs = inputs.runs
    metric = primary_metric(runs)
    ids = {run.path.resolve(): f"r{k}" for k, run in enumerate(runs)}
    by_id = {ids[run.path.resolve()]: run for run in runs}
    same_plan = [[ids[a.path.resolve()], ids[b.path.resolve()]] for a, b in policy_pairs(runs)]
    for session in sessions_json(inputs.pair_dirs, ids):
        members = [p["run"] for p in session["policies"] if p["run"]]
        same_plan += [[a, b] for i, a in enumerate(members) for b in members[i + 1 :] if [a, b] not in same_plan]
    return {
        "stamp": stamp(inputs),
        "live": live and not all(run.complete for run in runs),
        "report": numbers.report_tables(runs, metric, inputs.pair_dirs),
        "runs": [run_json(run_id, run, metric) for run_id, run in by_id.items()],
        "sessions": sessions_json(inputs.pair_dirs, ids),
        "same_plan": same_plan,
        "notes": inputs.notes,
    }


class Pages:
    """The document for a live page: reloaded from the run directories when their files change, once per change."""

    def __init__(self, specs: list[str]) -> None:
        self.specs = specs
        self._lock = threading.Lock()
        self._inputs = load_inputs(specs)
        self._doc = build(self._inputs, live=True)

    def current(self) -> dict[str, Any]:
        with self._lock:
            if stamp(self._inputs) != self._doc["stamp"]:
                self._inputs = load_inputs(self.specs)
                self._doc = build(self._inputs, live=True)
            return self._doc

    def run_dir(self, run_id: str) -> Path | None:
        """The directory of the page's run `run_id` (r0, r1, ...), or None."""
        with self._lock:
            runs = {f"r{k}": run for k, run in enumerate(self._inputs.runs)}
        return None if run_id not in runs else runs[run_id].path

    def dataset(self, run_id: str) -> Dataset | None:
        path = self.run_dir(run_id)
        return None if path is None else _dataset(path)


_DATASETS: dict[Path, Dataset] = {}


def _dataset(path: Path) -> Dataset:
    """One reader per run directory, so its episode index is read once."""
    key = path.resolve()
    if key not in _DATASETS or not _DATASETS[key].info:
        _DATASETS[key] = Dataset(path)
    return _DATASETS[key]
