"""comparison.md, the combined report of an interleaved run: each policy's results, the paired differences
overall and per perturbation with 95% cluster-bootstrap intervals, the sequential decisions and the restaging cost."""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import pandas as pd

from lerobot_contrast.contrast.metrics import METRIC_NAMES, METRICS
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.pairing.pair_dir import read_index
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.analysis import rng
from lerobot_contrast.reporting.markdown import fmt, num, table


def comparison_lines(path: Path) -> list[str]:
    """The interleaved comparison's section for the pair directory `path`."""
    entries = read_index(path)
    frames = {e["label"]: stats.frame(read_journal(path / e["name"] / "journal.jsonl")) for e in entries}
    summary = (
        json.loads((path / "summary.json").read_text(encoding="utf-8")) if (path / "summary.json").is_file() else {}
    )
    lines = [f"## Interleaved comparison: {path.name}", "", *_session_lines(summary), ""]
    lines += ["### Each policy", "", *table(
        ["policy", "done trials", *(METRIC_NAMES[m] for m in METRICS)],
        [[label, str(len(stats.done(df))), *(fmt(stats.metric_estimate(df, m)) for m in METRICS)]
         for label, df in frames.items()],
    ), ""]  # fmt: skip
    for a, b in itertools.combinations(frames, 2):
        lines += _pair_lines(a, b, frames[a], frames[b])
    return lines


def _session_lines(summary: dict[str, Any]) -> list[str]:
    if not summary:
        return ["The session has not written its summary yet."]
    cost, unit = summary["cost"], summary.get("cost_unit", "")
    out = [
        f"Each trial was staged once and run by every policy in turn, the scene restaged to its start between them; "
        f"the order rotated by base. Staging {num(cost['staging'], '.2f')} {unit}, restaging "
        f"{num(cost['restaging'], '.2f')} {unit} ({100 * cost['restage_share']:.0f}% of the cost).",
    ]
    stopping = summary.get("stopping") or {}
    if stopping.get("pairs"):
        out += ["", f"Sequential paired test ({stopping['metric']}, per base; {stopping['correction']}, "
                f"family-wise alpha {stopping['alpha']:g}): {stopping['why']}.", ""]  # fmt: skip
        out += table(
            ["first", "second", "anytime-valid interval", "verdict", "decided after bases"],
            [[p["first"], p["second"], f"[{p['difference_interval'][0]:+.3f}, {p['difference_interval'][1]:+.3f}]",
              p["verdict"], str(p["decided_at_bases"] or "-")] for p in stopping["pairs"]],
        )  # fmt: skip
    return out


def _pair_lines(a: str, b: str, left: pd.DataFrame, right: pd.DataFrame) -> list[str]:
    """Paired differences a - b, overall and per perturbation, over trials both did."""
    groups = [("all", left, right)]
    for name in pd.unique(left["perturbation"].fillna("original")):
        keep = lambda df, n=name: df[df["perturbation"].fillna("original") == n]  # noqa: E731
        groups.append((perturbation_label(None if name == "original" else name), keep(left), keep(right)))
    rows = []
    for label, x, y in groups:
        differences = {m: stats.paired_difference(x, y, m, rng()) for m in METRICS}
        n = max(e.n_trials for e in differences.values())
        rows.append([label, str(n), *(fmt(differences[m]) for m in METRICS)])
    title = f"### {a} minus {b}"
    note = "Mean per-trial difference over trials done by both; 95% cluster bootstrap interval over base instances."
    return [title, "", note, "", *table(["trials", "paired", *(f"Δ {METRIC_NAMES[m]}" for m in METRICS)], rows), ""]


def write_comparison(path: Path) -> Path:
    out = path / "comparison.md"
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text("\n".join(["# Interleaved evaluation", "", *comparison_lines(path)[2:]]) + "\n", encoding="utf-8")
    tmp.replace(out)
    return out


def append_comparisons(report: Path, pairs: list[Path]) -> Path:
    """report.md with each interleaved run's comparison added before its figures."""
    if not pairs:
        return report
    text = report.read_text(encoding="utf-8")
    head, mark, tail = text.partition("## Figures")
    added = "\n".join(line for path in pairs for line in comparison_lines(path)) + "\n\n"
    tmp = report.with_name(report.name + ".tmp")
    tmp.write_text(head + added + mark + tail, encoding="utf-8")
    tmp.replace(report)
    return report
