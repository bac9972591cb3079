"""The report's tables for the page: the same analysis functions and the same formatting as report.md, as rows."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.metrics import METRIC_NAMES
from lerobot_contrast.reporting import analysis, markdown
from lerobot_contrast.reporting.runs import Group, Run, group_runs, policy_pairs


def _table(title: str, intro: str, header: list[str], rows: list[list[str]], keys: list[str] | None = None) -> dict:
    """One table; `keys` names what each row stands for (a perturbation the page opens on a click)."""
    return {"title": title, "intro": intro, "header": header, "rows": rows, "keys": keys or []}


def summary_table(groups: list[Group], unit: str) -> dict[str, Any]:
    lines = markdown.summary_section(analysis.summary_rows(groups), unit)
    header, *rows = _rows(lines)
    return _table("Summary", lines[-2], header, rows)


def perturbation_table(groups: list[Group], metric: str) -> dict[str, Any]:
    """Per perturbation: each group's metric (n trials) and its paired change against the same bases' originals."""
    name = METRIC_NAMES[metric]
    order = analysis.perturbation_order(groups)
    values = analysis.by_column(groups, "perturbation", metric)
    with_perturbations = [g for g in groups if g.pooled["perturbation"].notna().any()]
    changes = analysis.sensitivities(with_perturbations, metric)
    names = [n for n in order if any(n in per for per in values.values())]
    header = ["perturbation"]
    for label in values:
        prefix = f"{label}: " if len(values) > 1 else ""
        header += [f"{prefix}{name}", f"{prefix}change vs originals"]
    rows = []
    for n in names:
        row = [markdown.perturbation_name(n)]
        for label, per in values.items():
            change = changes.get(label, {}).get(n)
            row += [markdown.fmt(per.get(n), True), "-" if n == "original" else markdown.fmt(change, True)]
        rows.append(row)
    intro = (
        f"{name} pooled over seeds (n = trials); the change is the mean over base instances of (perturbed trial - its "
        "own base's original), 95% interval by bootstrap over bases, as in report.md."
    )
    return _table(f"{name} per perturbation", intro, header, rows, names)


def family_table(groups: list[Group], metric: str) -> dict[str, Any]:
    families = sorted({f for g in groups for f in g.pooled["family"]})
    values = analysis.by_column(groups, "family", metric)
    lines = markdown.by_group_section(f"{METRIC_NAMES[metric]} per task family", "", values, families, label=str)
    header, *rows = _rows(lines)
    return _table(lines[0][3:], "Pooled over seeds; n = trials.", header, rows)


def versus_table(groups: list[Group], runs: list[Run], metric: str) -> dict[str, Any] | None:
    """The estimation error at the standard run's cost, where a full i.i.d. reference is among the runs."""
    versus = analysis.versus_full(groups, runs, metric)
    if not versus:
        return None
    lines = markdown.versus_section(versus, metric, runs[0].cost_unit, None)
    header, *rows = _rows(lines)
    return _table("Against the full i.i.d. evaluation", lines[2], header, rows)


def comparison_table(runs: list[Run]) -> dict[str, Any] | None:
    lines = markdown.comparison_section(analysis.comparisons(policy_pairs(runs)))
    if not lines:
        return None
    header, *rows = _rows(lines)
    return _table("Policies on the same plan", lines[2], header, rows)


def sequential_table(runs: list[Run]) -> dict[str, Any] | None:
    lines = markdown.sequential_section(runs)
    if not lines:
        return None
    header, *rows = _rows(lines)
    return _table("Sequential stopping", lines[-2], header, rows)


def _rows(lines: list[str]) -> list[list[str]]:
    """The header and rows of the Markdown table in a section of report.md, as `markdown.table` wrote them (no cell
    holds a '|'): the page shows report's own strings."""
    table = [line for line in lines if line.startswith("|") and not line.startswith("|---")]
    return [[cell.strip() for cell in line.strip().strip("|").split("|")] for line in table]


def session_tables(pair_dir: Path) -> list[dict[str, Any]]:
    """The interleaved comparison `report` adds for an A/B session (`--policies`): its sequential decisions, each
    policy's results and the paired differences, one table per Markdown table, titled by its heading."""
    from lerobot_contrast.pairing.comparison import comparison_lines

    tables, heading, text, rows = [], "", "", []
    for line in [*comparison_lines(pair_dir), ""]:
        if line.startswith("|"):
            rows.append(line)
            continue
        if rows:
            header, *body = _rows(rows)
            title = f"{pair_dir.name}: {heading}" if heading else f"{pair_dir.name}: the sequential paired test"
            tables.append(_table(title, text, header, body))
            rows, text = [], ""
        if line.startswith("### "):
            heading = line[4:]
        elif line and not line.startswith("#"):
            text = line
    return tables


def report_tables(runs: list[Run], metric: str | None = None, pair_dirs: list[Path] = ()) -> dict[str, Any]:
    """Every table of report.md the page shows (with an A/B session's comparison, as `report` adds it), with the
    metric it is about."""
    metric = metric or analysis.primary_metric(runs)
    groups = group_runs(runs)
    tables = [
        summary_table(groups, runs[0].cost_unit),
        perturbation_table(groups, metric),
        family_table(groups, metric),
        versus_table(groups, runs, metric),
        comparison_table(runs),
        sequential_table(runs),
        *(table for path in pair_dirs for table in session_tables(path)),
    ]
    return {
        "metric": metric,
        "metric_name": METRIC_NAMES[metric],
        "groups": [{"label": g.label, "runs": [r.name for r in g.runs]} for g in groups],
        "tables": [t for t in tables if t is not None],
        "notes": [line[2:] for line in markdown.notes_section(runs) if line.startswith("- ")],
    }
