"""The table at the end of a run: per perturbation its trials, the metric, and its change paired against the same
bases' originals (as `report` computes it), then the overall row with its interval."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.analysis import rng

ORIGINAL = "original"
METRIC_TITLES = {"spl": "SPL", "progress": "progress", "success": "success"}
COUNTS = {"trials": 7, "not_applicable": 6, "aborted": 9, "skipped": 9}
COUNT_TITLES = {"not_applicable": "n/a"}


def table_metric(records: Iterable[TrialRecord]) -> str:
    """SPL where the run recorded it, else subgoal progress, else success."""
    done = [r for r in records if r.status == "done"]
    for metric in ("spl", "progress"):
        if any(getattr(r, metric) is not None for r in done):
            return metric
    return "success"


def _interval(estimate: stats.Estimate, signed: bool = False) -> str:
    if estimate.n_trials == 0 or math.isnan(estimate.mean):
        return "-"
    pattern = "{:+.3f}" if signed else "{:.3f}"

    def fmt(value: float) -> str:
        return pattern.format(round(value, 3) + 0.0)  # no "-0.000"

    if math.isnan(estimate.low):  # one base: no interval
        return fmt(estimate.mean)
    return f"{fmt(estimate.mean)} [{fmt(estimate.low)}, {fmt(estimate.high)}]"


def _fmt(value: float | None, pattern: str = "{:.3f}") -> str:
    return "-" if value is None else pattern.format(value)


def results_table(records: list[TrialRecord], summary: Mapping[str, Any], unit: str) -> str:
    """The end-of-run table and one line on how to read it."""
    metric = table_metric(records)
    title = METRIC_TITLES[metric]
    df = stats.frame(records)
    changes = stats.paired_sensitivity(df, metric, rng()) if len(df) else {}
    rows, total = summary["per_perturbation"], summary["overall"]
    names = list(dict.fromkeys(name for name in [ORIGINAL, *rows] if name in rows))  # the originals first
    counts = ["trials", "not_applicable"] + (["aborted", "skipped"] if total["aborted"] or total["skipped"] else [])
    show_success = metric != "success"
    header = (
        f"{'perturbation':<14}"
        + "".join(f"{COUNT_TITLES.get(k, k):>{COUNTS[k]}}" for k in counts)
        + (f"{'success':>9}" if show_success else "")
        + f"  {title:<23}  {'change vs originals':<24}{'cost (' + unit + ')':>11}"
    )

    def line(label: str, s: Mapping[str, Any], value: str, change: str, cost: float) -> str:
        return (
            f"{label:<14}"
            + "".join(f"{s[k]:>{COUNTS[k]}}" for k in counts)
            + (f"{_fmt(s['success_rate']):>9}" if show_success else "")
            + f"  {value:<23}  {change:<24}{_fmt(cost, '{:.2f}'):>11}"
        )

    lines = [header, "-" * len(header)]
    for name in names:
        value = _fmt(rows[name].get(_SUMMARY_KEYS[metric]))
        change = "-" if name == ORIGINAL else _interval(changes[name], signed=True) if name in changes else "-"
        label = perturbation_label(None if name == ORIGINAL else name)
        lines.append(line(label, rows[name], value, change, rows[name]["cost"]))
    overall = _interval(stats.metric_estimate(df, metric)) if len(df) else "-"
    lines += ["-" * len(header), line("all", total, overall, "", total["cumulative_cost"])]
    stopping = summary.get("stopping")
    if stopping is not None and stopping["metric"] == metric:
        low, high = stopping["anytime_interval"]
        column = 14 + sum(COUNTS[k] for k in counts) + (9 if show_success else 0) + 2
        level = f"{100 * (1 - stopping['alpha']):g}%"
        lines.append(f"{'':<{column}}[{low:.3f}, {high:.3f}] anytime-valid {level}, the stopping rule's")
    lines.append(how_to_read(title))
    return "\n".join(lines)


_SUMMARY_KEYS = {"spl": "spl", "progress": "progress", "success": "success_rate"}


def how_to_read(title: str) -> str:
    return (
        f"How to read: the change is paired (same base instances, 95% interval over bases); a perturbation runs only "
        f"where it applies, so its {title} is not comparable with the originals' row. all: fixed-n 95% interval."
    )
