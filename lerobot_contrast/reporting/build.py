"""Assemble a report: analyse the runs, draw the figures and write report.md next to them."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lerobot_contrast.reporting import analysis, figures, markdown, stats
from lerobot_contrast.reporting.audit import audit_section
from lerobot_contrast.reporting.runs import Group, Run, group_runs, policy_label, policy_pairs, reference_for


@dataclass
class Report:
    """What a report found, for callers that go on to use the numbers (the paper reproduction does)."""

    path: Path  # report.md
    metric: str
    groups: list[Group]
    versus: list[analysis.VersusFull]
    figures: list[Path]


def why_no_reference(runs: list[Run]) -> str:
    if not any(r.config.get("strategy") == "standard" for r in runs):
        return (
            "no standard run among the inputs; add the complete standard evaluation (--strategy=standard, no "
            "--budget) of the same policy, evaluation set and seed."
        )
    return (
        "the standard runs among the inputs are incomplete, budgeted, or of another policy, evaluation set or "
        "seed than the other runs; add a complete, unbudgeted one that matches."
    )


def full_values(runs: list[Run], metric: str) -> dict[str, float]:
    """The full i.i.d. value per policy (the mean over the seeds of its standard runs): a mean over two policies
    would be neither's."""
    by_policy: dict[str, list[float]] = {}
    for ref in (ref for run in runs if (ref := reference_for(run, runs)) is not None):
        by_policy.setdefault(policy_label(ref.config), []).append(stats.full_value(ref.results, metric))
    return {policy: float(np.mean(values)) for policy, values in by_policy.items()}


def draw(runs: list[Run], groups: list[Group], versus, metric: str, output_dir: Path) -> list[Path]:
    """The paper's left panel (per perturbation), right panel (error vs cost) and appendix (trials vs cost)."""
    unit = runs[0].cost_unit
    colors = figures.color_of([g.label for g in groups])
    references = [ref for run in runs if (ref := reference_for(run, runs)) is not None]
    full = full_values(runs, metric)
    per_perturbation = analysis.by_column(groups, "perturbation", metric)
    contrast = {g.label: per_perturbation[g.label] for g in groups if g.runs[0].config.get("strategy") == "contrast"}
    shown = analysis.with_overall(contrast or per_perturbation, groups, metric)
    order = ["all", *analysis.perturbation_order(groups)]
    paths = [
        figures.save(
            figures.perturbation_plot(shown, order, metric, full, colors), output_dir / f"perturbations_{metric}.png"
        )
    ]
    if versus:
        paths.append(figures.error_figure(versus, metric, unit, colors, output_dir / f"error_vs_cost_{metric}.png"))
    costs, curves = analysis.trials_curves(groups, n_bins=200)
    reference_cost = float(np.mean([stats.total_cost(r.results) for r in references])) if references else None
    paths.append(figures.trials_figure(costs, curves, unit, colors, output_dir / "trials_vs_cost.png", reference_cost))
    return paths


def write_markdown(runs: list[Run], groups: list[Group], versus, metric: str, paths: list[Path]) -> str:
    unit, name = runs[0].cost_unit, figures.METRIC_NAMES[metric]
    order = analysis.perturbation_order(groups)
    families = sorted({f for g in groups for f in g.pooled["family"]})
    with_perturbations = [g for g in groups if g.pooled["perturbation"].notna().any()]
    lines = [
        "# Contrast-set evaluation report",
        "",
        f"{len(runs)} run(s) in {len(groups)} design(s); main metric: {name}.",
        "",
    ]
    lines += markdown.summary_section(analysis.summary_rows(groups), unit)
    lines += markdown.sequential_section(runs)
    lines += markdown.robot_staging_section(runs)
    lines += audit_section(runs)
    pooled = "Pooled over seeds; n = trials."
    lines += markdown.by_group_section(
        f"{name} per perturbation", pooled, analysis.by_column(groups, "perturbation", metric), order
    )
    if with_perturbations:
        lines += markdown.by_group_section(
            f"Sensitivity: {name} change from the same base instance",
            "Mean over base instances of (perturbed trial - its own base's original trial); interval: bootstrap over bases.",
            analysis.sensitivities(with_perturbations, metric),
            order[1:],
        )
    lines += markdown.by_group_section(
        f"{name} per task family", pooled, analysis.by_column(groups, "family", metric), families, label=str
    )
    lines += markdown.versus_section(versus, metric, unit, None if versus else why_no_reference(runs))
    lines += markdown.comparison_section(analysis.comparisons(policy_pairs(runs)))
    lines += ["## Figures", "", *(f"![{p.stem}]({p.name})" for p in paths), ""]
    lines += markdown.notes_section(runs)
    lines += markdown.settings_section(runs)
    return "\n".join(lines)


def build_report(runs: list[Run], output_dir: Path, metric: str | None = None) -> Report:
    """Write report.md and the figures into `output_dir`."""
    output_dir.mkdir(parents=True, exist_ok=True)
    metric = metric or analysis.primary_metric(runs)
    groups = group_runs(runs)
    versus = analysis.versus_full(groups, runs, metric)
    paths = draw(runs, groups, versus, metric, output_dir)
    path = output_dir / "report.md"
    tmp = path.with_name(path.name + ".tmp")  # written last and whole, so a report.md is never partial
    tmp.write_text(write_markdown(runs, groups, versus, metric, paths), encoding="utf-8")
    os.replace(tmp, path)
    return Report(path, metric, groups, versus, paths)
