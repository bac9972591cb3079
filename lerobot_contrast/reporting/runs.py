"""Run directories as report inputs: loading, labels, grouping over seeds, and matching runs for comparisons."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.policies.base import DEFAULT_POLICY
from lerobot_contrast.record.hub import parse_hub_spec, resolve_run
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.record.results import read_results
from lerobot_contrast.record.run_dir import comparable_settings
from lerobot_contrast.record.sweep_dir import cell_run_dirs, is_sweep_dir
from lerobot_contrast.reporting.stats import frame

# Settings that say how a run was recorded or where its plan came from, not what it evaluated (besides those
# a run may change between sessions, see comparable_settings).
RECORDING_KEYS = ("plan", "rerun", "record_dataset")
# Columns that, with the config, identify a run: the same trials started at the same times are the same run,
# whether read from a local directory or its copy downloaded from the Hub.
IDENTITY_COLUMNS = ("index", "instance_id", "status", "started_at", "cost", "success", "spl", "progress")
# Settings a strategy may differ in from the standard run that serves as its full i.i.d. reference.
STRATEGY_KEYS = ("strategy", "perturbations", "order", "budget")


class ReportInputError(UserError):
    pass


@dataclass
class Run:
    """One run directory: its settings, summary (when written) and results table."""

    path: Path
    config: dict[str, Any]
    summary: dict[str, Any]
    results: pd.DataFrame

    @property
    def name(self) -> str:
        return self.path.name

    @property
    def seed(self) -> Any:
        return self.config.get("seed")

    @property
    def complete(self) -> bool:
        return bool(self.summary.get("complete", False))

    @property
    def cost_unit(self) -> str:
        return self.summary.get("settings", {}).get("cost_unit") or {"reset_time": "s"}.get(
            self.config.get("cost"), "m"
        )

    @property
    def identity(self) -> str:
        """A hash of the config and the trials (ids, outcomes, start times), the same for a run and its Hub copy."""
        trials = self.results[[c for c in IDENTITY_COLUMNS if c in self.results]].sort_values("index")
        config = json.dumps(self.config, sort_keys=True, default=str)
        rows = trials.astype(str).to_json(orient="values")
        return hashlib.sha256(f"{config}\n{rows}".encode()).hexdigest()

    @property
    def is_full_iid(self) -> bool:
        """A complete, unbudgeted standard evaluation: the reference the other strategies are judged against."""
        return self.config.get("strategy") == "standard" and self.config.get("budget") is None and self.complete


def load_run(spec: str) -> Run:
    """Load a report input: a local run directory (holding config.json and journal.jsonl or results.parquet),
    or `hub:USER/NAME[@REVISION]`, a run published with `lerobot_contrast.publish` (downloaded first)."""
    path = resolve_run(spec)
    if not path.is_dir():
        raise ReportInputError(f"{spec}: no such run directory; pass directories written by lerobot_contrast.eval")
    config_path = path / "config.json"
    if not config_path.exists():
        raise ReportInputError(
            f"{spec}: not a run directory (no config.json); pass the folder lerobot_contrast.eval wrote"
        )
    config = _read_json(config_path)
    summary = _read_json(path / "summary.json") if (path / "summary.json").exists() else {}
    return Run(path=path, config=config, summary=summary, results=_read_trials(path))


def run_specs(specs: list[str]) -> list[str]:
    """The report inputs with each sweep folder (written by lerobot_contrast.sweep) replaced by its cells' run
    directories."""
    out = []
    for spec in specs:
        if parse_hub_spec(spec) is not None or not is_sweep_dir(Path(spec)):
            out.append(spec)
            continue
        cells = cell_run_dirs(Path(spec))
        if not cells:
            raise ReportInputError(f"{spec}: a sweep folder none of whose cells has started; run the sweep first")
        out += [str(cell) for cell in cells]
    return out


def distinct_runs(specs: list[str], runs: list[Run]) -> tuple[list[Run], list[str]]:
    """Each run once, however many times it was given (locally, from the Hub, or both); and one line per repeat."""
    first: dict[str, str] = {}
    kept, notes = [], []
    for spec, run in zip(specs, runs, strict=True):
        if run.identity in first:
            notes.append(f"{spec} is the same run as {first[run.identity]}; it is counted once")
            continue
        first[run.identity] = spec
        kept.append(run)
    return kept, notes


def _read_json(path: Path) -> dict[str, Any]:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as error:
        raise ReportInputError(f"{path}: not valid JSON ({error.msg}, line {error.lineno})") from None


def _read_trials(path: Path) -> pd.DataFrame:
    """The journal is the record of truth (results.parquet is only rewritten when a run stops); it is read
    without touching it, so a report never repairs the journal of a run still writing it."""
    journal = path / "journal.jsonl"
    if journal.exists():
        return frame(read_journal(journal))
    if (path / "results.parquet").exists():
        try:
            return frame(read_results(path / "results.parquet"))
        except ValueError as error:
            raise ReportInputError(str(error)) from None
    raise ReportInputError(f"{path}: holds no trials (no journal.jsonl or results.parquet)")


def design(config: dict[str, Any], drop: tuple[str, ...] = ()) -> str:
    """The settings that define what a run evaluated, as a comparable key, leaving out `drop`."""
    kept = {k: v for k, v in comparable_settings(config).items() if k not in RECORDING_KEYS + drop}
    return json.dumps(kept, sort_keys=True, default=str)


def strategy_label(run: Run) -> str:
    """e.g. "standard", "contrast ΔLB1+ΔLB2", "contrast ΔLB1+ΔLB2+ΔSB1+ΔSB2, cost-aware order"."""
    config = run.config
    label = str(config.get("strategy"))
    if label == "contrast":
        names = config.get("perturbations") or list(pd.unique(run.results["perturbation"].dropna()))
        label += " " + "+".join(perturbation_label(n) for n in names)
    if config.get("order", "iid") != "iid":
        label += f", {str(config['order']).replace('_', '-')} order"
    if config.get("budget") is not None:
        label += f", budget {config['budget']:g}"
    return label


def policy_label(config: dict[str, Any]) -> str:
    policy = config.get("policy") or {}
    label = str(policy.get("path") or policy.get("type") or DEFAULT_POLICY)
    extras = [f"{key.replace('_', ' ')} {policy[key]:g}" for key in ("noise_std", "language_blind") if policy.get(key)]
    return label + (f" ({', '.join(extras)})" if extras and not policy.get("path") else "")


@dataclass
class Group:
    """Runs of one design over seeds."""

    label: str
    runs: list[Run]

    @property
    def pooled(self) -> pd.DataFrame:
        """All runs' trials, with base and instance ids made unique per seed so clusters stay per base."""
        frames = []
        for k, run in enumerate(self.runs):
            df = run.results.copy()
            df["base_id"] = f"{k}:" + df["base_id"].astype(str)
            df["instance_id"] = f"{k}:" + df["instance_id"].astype(str)
            frames.append(df)
        return pd.concat(frames, ignore_index=True)


def group_runs(runs: list[Run]) -> list[Group]:
    """Runs that differ only in seed form one group, in input order; labels name the policy when they differ."""
    groups: dict[str, list[Run]] = {}
    for run in runs:
        groups.setdefault(design(run.config, drop=("seed",)), []).append(run)
    policies = {policy_label(run.config) for run in runs}
    out = []
    for members in groups.values():
        label = strategy_label(members[0])
        if len(policies) > 1:
            label = f"{policy_label(members[0].config)}: {label}"
        out.append(Group(label, sorted(members, key=lambda r: str(r.seed))))
    return out


def reference_for(run: Run, runs: list[Run]) -> Run | None:
    """The full i.i.d. evaluation of the same policy, evaluation set and seed, if among `runs`."""
    key = design(run.config, drop=STRATEGY_KEYS)
    return next((r for r in runs if r.is_full_iid and design(r.config, drop=STRATEGY_KEYS) == key), None)


def policy_pairs(runs: list[Run]) -> list[tuple[Run, Run]]:
    """Pairs of runs with the same plan (every setting but the policy equal), for paired comparisons."""
    pairs = []
    for i, a in enumerate(runs):
        for b in runs[i + 1 :]:
            if design(a.config, drop=("policy",)) == design(b.config, drop=("policy",)) and a.config.get(
                "policy"
            ) != b.config.get("policy"):
                pairs.append((a, b))
    return pairs
