"""The run summary (`summary.json`) and its console table: trials, cost and mean metrics per perturbation."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable
from typing import Any

from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.contrast.trial import TrialRecord

SUMMARY_VERSION = 1
ORIGINAL = "original"


def _mean(values: list[float]) -> float | None:
    return sum(values) / len(values) if values else None


def _group_stats(records: list[TrialRecord]) -> dict[str, Any]:
    done = [r for r in records if r.status == "done"]
    return {
        "trials": len(done),
        "not_applicable": sum(r.status == "not_applicable" for r in records),
        "aborted": sum(r.status == "aborted" for r in records),
        "skipped": sum(r.status == "skipped" for r in records),
        "success_rate": _mean([float(bool(r.success)) for r in done]),
        "spl": _mean([r.spl for r in done if r.spl is not None]),
        "progress": _mean([r.progress for r in done if r.progress is not None]),
        "cost": sum(r.cost for r in done),
    }


def summarize(
    records: Iterable[TrialRecord], *, settings: dict[str, Any], complete: bool, stopping: dict[str, Any] | None = None
) -> dict[str, Any]:
    """`stopping`: the sequential stopping rules' account of the run (why it stopped, its anytime-valid intervals)."""
    records = list(records)
    by_perturbation: dict[str, list[TrialRecord]] = defaultdict(list)
    by_family: dict[str, list[TrialRecord]] = defaultdict(list)
    for record in records:
        by_perturbation[record.perturbation or ORIGINAL].append(record)
        by_family[record.family].append(record)
    done = [r for r in records if r.status == "done"]
    return {
        "version": SUMMARY_VERSION,
        "complete": complete,
        "settings": settings,
        "overall": {
            **_group_stats(records),
            "cumulative_cost": done[-1].cumulative_cost if done else 0.0,
            "wall_time_s": sum(r.duration_s or 0.0 for r in done),
        },
        **_robot_staging(done),
        "per_perturbation": {name: _group_stats(group) for name, group in by_perturbation.items()},
        "per_family": {name: _group_stats(group) for name, group in sorted(by_family.items())},
        **({} if stopping is None else {"stopping": stopping}),
    }


def _robot_staging(done: list[TrialRecord]) -> dict[str, Any]:
    """Where the arm staged trials itself (--operator=arm): its seconds of staging and the person's calls, the
    paper's experimenter cost beside the metres moved."""
    staged = [r.extra for r in done if "robot_s" in r.extra]
    if not staged:
        return {}
    return {
        "robot_staging": {
            "trials": len(staged),
            "robot_s": round(sum(e["robot_s"] for e in staged), 2),
            "interventions": sum(e.get("interventions", 0) + int(e.get("label_asked", False)) for e in staged),
            "unlabelled": sum(bool(e.get("unlabelled")) for e in staged),
        }
    }


def _fmt(value: float | None, pattern: str = "{:.3f}") -> str:
    return "-" if value is None else pattern.format(value)


def format_summary(summary: dict[str, Any], unit: str) -> str:
    """A plain-text table: one row per perturbation (the original instances first), then the total. The aborted
    and skipped columns appear when some trial was aborted or skipped (never in a simulator)."""
    rows = summary["per_perturbation"]
    names = list(dict.fromkeys(name for name in [ORIGINAL, *rows] if name in rows))  # the originals first
    total = summary["overall"]
    counts = ["trials", "not_applicable"] + (["aborted", "skipped"] if total["aborted"] or total["skipped"] else [])
    widths = {"trials": 7, "not_applicable": 6, "aborted": 9, "skipped": 9}
    titles = {"not_applicable": "n/a"}
    header = (
        f"{'perturbation':<14}"
        + "".join(f"{titles.get(k, k):>{widths[k]}}" for k in counts)
        + f"{'success':>9}{'SPL':>8}{'cost (' + unit + ')':>12}"
    )

    def line(label: str, s: dict[str, Any], cost: float | None) -> str:
        return (
            f"{label:<14}"
            + "".join(f"{s[k]:>{widths[k]}}" for k in counts)
            + f"{_fmt(s['success_rate']):>9}{_fmt(s['spl']):>8}{_fmt(cost, '{:.2f}'):>12}"
        )

    lines = [header, "-" * len(header)]
    for name in names:
        label = perturbation_label(None if name == ORIGINAL else name)
        lines.append(line(label, rows[name], rows[name]["cost"]))
    lines += ["-" * len(header), line("all", total, total["cumulative_cost"])]
    robot = summary.get("robot_staging")
    if robot:
        lines.append(
            f"staged by the arm: {robot['trials']} trials, {robot['robot_s']:.0f} robot seconds, a person called "
            f"{robot['interventions']} times, {robot['unlabelled']} left unlabelled for review"
        )
    return "\n".join(lines)
