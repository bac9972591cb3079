"""report.md: the tables of a report as Markdown."""

from __future__ import annotations

import math
from typing import Any

from lerobot_contrast.contrast.metrics import METRIC_NAMES, METRICS
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.analysis import Comparison, SummaryRow, VersusFull
from lerobot_contrast.reporting.runs import Run

METHODS = {
    "korn_graubard": "fixed-n: Korn-Graubard interval (Clopper-Pearson at the effective sample size of the "
    "base-instance clusters, t degrees of freedom)",
    "cluster_bootstrap": "cluster bootstrap over base instances (2,000 resamples, small-sample widened percentile)",
}


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return lines + ["| " + " | ".join(row) + " |" for row in rows]


def num(x: float, spec: str = ".3f") -> str:
    """`x` to three decimals, with no `-0.000`: a value that rounds to zero has no sign."""
    return format(round(x, 3) + 0.0, spec)


def fmt(e: stats.Estimate | None, with_n: bool = False) -> str:
    if e is None or e.n_trials == 0:
        return "-"
    interval = "" if math.isnan(e.low) else f" [{num(e.low)}, {num(e.high)}]"
    return f"{num(e.mean)}{interval}" + (f" (n={e.n_trials})" if with_n else "")


def summary_section(rows: list[SummaryRow], unit: str) -> list[str]:
    header = ["run", "seed", "trials", "n/a", "aborted", "skipped", f"cost ({unit})", f"trials per {unit}"]
    header += [METRIC_NAMES[m] for m in METRICS]
    body = [
        [r.label, r.seeds, *(str(r.counts[s]) for s in stats.STATUSES), f"{r.cost:.1f}", f"{r.trials_per_cost:.2f}"]
        + [fmt(r.estimates[m]) for m in METRICS]
        for r in rows
    ]
    used = sorted({e.method for r in rows for e in r.estimates.values() if e.method in METHODS})
    notes = [
        "",
        "Only trials with status done count toward the metrics. 95% intervals: "
        + "; ".join(METHODS[m] for m in used)
        + ".",
    ]
    return ["## Summary", "", *table(header, body), *notes, ""]


def perturbation_name(name: str) -> str:
    return perturbation_label(None if name == "original" else name)


def by_group_section(
    title: str, intro: str, data: dict[str, dict[str, stats.Estimate]], order: list[str], label=perturbation_name
) -> list[str]:
    """One row per perturbation (or family) in `order`, one column per group."""
    names = [n for n in order if any(n in per for per in data.values())]
    header = ["", *data]
    body = [[label(n), *(fmt(per.get(n), True) for per in data.values())] for n in names]
    return [f"## {title}", "", intro, "", *table(header, body), ""]


def versus_section(versus: list[VersusFull], metric: str, unit: str, why_missing: str | None) -> list[str]:
    lines = ["## Against the full i.i.d. evaluation", ""]
    if not versus:
        return lines + [f"No estimation-error panel: {why_missing}", ""]
    name = METRIC_NAMES[metric]
    lines.append(
        f"The full i.i.d. value is the mean {name} of the complete, unbudgeted standard evaluation of the same "
        "policy, evaluation set and seed. An estimate within a budget uses the trials whose cumulative cost is "
        "within it. Means over seeds."
    )
    header = ["strategy", "seeds", f"standard's cost ({unit})", "trials at that cost", "x standard's trials"]
    header += [
        f"{name} error at that cost (signed)",
        f"abs. {name} error at that cost",
        f"abs. {name} error at the run's end",
    ]
    body = [
        [v.label, str(v.seeds), f"{v.reference_costs.mean():.1f}", f"{v.trials_at_reference.mean():.0f}"]
        + [f"{(v.trials_at_reference / v.reference_trials).mean():.2f}", num(v.signed_at_reference.mean(), "+.3f")]
        + [num(v.error_at_reference), num(v.error_at_end)]
        for v in versus
    ]
    return lines + ["", *table(header, body), ""]


def comparison_section(items: list[Comparison]) -> list[str]:
    if not items:
        return []
    lines = [
        "## Policies on the same plan",
        "",
        "Mean per-trial difference (first minus second) over trials with the same instance id done by both, with a cluster bootstrap interval over base instances.",
        "",
    ]
    header = ["first", "second", "paired trials", *(f"Δ {METRIC_NAMES[m]}" for m in METRICS)]
    body = []
    for c in items:
        n = max(e.n_trials for e in c.differences.values())
        body.append([f"{c.a.name}", f"{c.b.name}", str(n), *(fmt(c.differences[m]) for m in METRICS)])
    return lines + [*table(header, body), ""]


# Settings of one session of a run rather than of the run.
SESSION_KEYS = ("output_dir", "resume", "dry_run")


def flatten(config: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in config.items():
        if isinstance(value, dict) and value:
            out.update(flatten(value, f"{prefix}{key}."))
        elif prefix or key not in SESSION_KEYS:
            out[prefix + key] = value
    return out


def used_settings(config: dict[str, Any]) -> dict[str, Any]:
    """The run's settings, with the task defaults that a None stands for written out as the values used."""
    from lerobot_contrast.contrast.errors import UserError
    from lerobot_contrast.domains import load_task

    out = flatten(config)
    try:
        task = load_task(config["task"], families=config.get("families"))
    except (UserError, KeyError, OSError):  # a published run of a task file this machine does not have
        return out
    if out.get("n_instances") is None:
        out["n_instances"] = task.default_instances
    if out.get("perturbations") is None:
        used = [p.name for p in task.perturbations] if config.get("strategy") == "contrast" else []
        out["perturbations"] = ",".join(used) or "none"
    return out


def settings_section(runs: list[Run]) -> list[str]:
    lines = ["## Settings of every run", ""]
    for run in runs:
        flags = ", ".join(f"`{k}={v}`" for k, v in used_settings(run.config).items())
        state = "complete" if run.complete else "incomplete (stopped early, or still running)"
        lines.append(f"- **{run.name}** (`{run.path}`, {state}): {flags}")
    return lines + [""]


def sequential_section(runs: list[Run]) -> list[str]:
    """Runs with --stop.* rules: why each stopped, and its anytime-valid interval beside the fixed-n one."""
    rows = []
    for run in runs:
        s = run.summary.get("stopping")
        if not s:
            continue
        level = f"{100 * (1 - s['alpha']):g}%"
        fixed, anytime = s["fixed_n_interval"], s["anytime_interval"]
        mean = "-" if s["mean"] is None else num(s["mean"])
        verdict = "-"
        if "verdict" in s:
            low, high = s["difference_interval"]
            verdict = f"{s['verdict']} than {s['compare']} [{num(low)}, {num(high)}]"
        rows.append(
            [run.name, s["why"], str(s["complete_bases"]), f"{s['metric']} {mean}",
             f"[{num(fixed[0])}, {num(fixed[1])}] ({level})", f"[{num(anytime[0])}, {num(anytime[1])}] ({level})",
             verdict]
        )  # fmt: skip
    if not rows:
        return []
    header = ["run", "stopped because", "bases", "mean", "fixed-n interval", "anytime-valid CS", "comparison"]
    note = (
        "The fixed-n interval is valid only for a number of bases fixed in advance; after stopping on the data, "
        "read the anytime-valid confidence sequence (betting, Waudby-Smith and Ramdas 2024), which holds at any "
        "stopping time. Both cover the mean over trials of the bases completed when the run stopped."
    )
    return ["## Sequential stopping", "", *table(header, rows), "", note, ""]


def robot_staging_section(runs: list[Run]) -> list[str]:
    """Runs the arm staged itself (--operator=arm): its seconds of staging and the person's calls, from the summary."""
    rows = []
    for run in runs:
        r = run.summary.get("robot_staging")
        if r:
            each = r["robot_s"] / r["trials"] if r["trials"] else 0.0
            rows.append([run.name, str(r["trials"]), f"{r['robot_s']:.0f}", f"{each:.1f}", str(r["interventions"]),
                         str(r["unlabelled"])])  # fmt: skip
    if not rows:
        return []
    header = ["run", "trials staged", "robot s", "robot s per trial", "person calls", "unlabelled"]
    return ["## Staged by the arm", "", *table(header, rows), ""]


def notes_section(runs: list[Run]) -> list[str]:
    notes = []
    for run in runs:
        if not run.complete:
            notes.append(f"{run.name} is incomplete: its numbers cover the trials recorded so far.")
        bases = run.results["base_id"].nunique()
        planned = run.config.get("n_instances")
        if run.config.get("order") == "adaptive":
            notes.append(
                f"{run.name} chose which perturbations to run on each base from earlier outcomes (--order=adaptive): "
                "its original instances' mean is an unbiased i.i.d. estimate, but its per-perturbation rows, "
                "sensitivities and pooled 'all' means are adaptive (which bases each covers depends on the outcomes), "
                "so read them as descriptive, with approximate intervals."
            )
        if run.config.get("order") == "cost_aware" and planned and bases < planned:
            notes.append(
                f"{run.name} visited {bases} of {planned} bases in cost-aware order: a prefix of a tour is not an "
                "i.i.d. sample, so its estimate may be biased; choose --n_instances so the whole tour fits the budget."
            )
    return ["## Notes", "", *(f"- {n}" for n in notes), ""] if notes else []
