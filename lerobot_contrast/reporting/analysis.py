"""The numbers a report shows: per-run and per-group estimates, and each strategy against the full i.i.d. run."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from lerobot_contrast.contrast.metrics import METRICS
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.runs import Group, Run, reference_for

SEED = 0  # bootstrap randomness: the same inputs give the same report


def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


def primary_metric(runs: list[Run]) -> str:
    """SPL, as in the paper, where the runs recorded it; else subgoal progress."""
    has_spl = any(stats.done(run.results)["spl"].notna().any() for run in runs)
    return "spl" if has_spl else "progress"


def perturbation_order(groups: list[Group]) -> list[str]:
    """Perturbation names, "original" first, then in the order the runs planned them."""
    names = ["original"]
    for group in groups:
        for name in group.pooled.sort_values("index")["perturbation"].dropna():
            if name not in names:
                names.append(name)
    return names


@dataclass
class SummaryRow:
    label: str
    seeds: str
    counts: dict[str, int]
    cost: float
    trials_per_cost: float
    estimates: dict[str, stats.Estimate]


def summary_row(label: str, seeds: str, df: pd.DataFrame, runs: list[Run]) -> SummaryRow:
    """Counts, mean total cost per run, trials per unit cost, and every metric with its interval."""
    cost = float(np.mean([stats.total_cost(r.results) for r in runs]))
    per_cost = float(np.mean([stats.trials_per_unit_cost(r.results) for r in runs]))
    estimates = {m: stats.metric_estimate(df, m) for m in METRICS}
    return SummaryRow(label, seeds, stats.status_counts(df), cost, per_cost, estimates)


def summary_rows(groups: list[Group]) -> list[SummaryRow]:
    """One row per run, then a pooled row for each group with several seeds."""
    rows = []
    for group in groups:
        for run in group.runs:
            rows.append(summary_row(group.label, str(run.seed), run.results, [run]))
        if len(group.runs) > 1:
            seeds = ",".join(str(r.seed) for r in group.runs)
            rows.append(summary_row(f"{group.label} (pooled)", seeds, group.pooled, group.runs))
    return rows


def by_column(groups: list[Group], column: str, metric: str) -> dict[str, dict[str, stats.Estimate]]:
    """Per group (pooled over seeds): the metric per perturbation or per family."""
    return {g.label: stats.grouped_estimates(g.pooled, column, metric) for g in groups}


def sensitivities(groups: list[Group], metric: str) -> dict[str, dict[str, stats.Estimate]]:
    return {g.label: stats.paired_sensitivity(g.pooled, metric, rng()) for g in groups}


@dataclass
class VersusFull:
    """A group against the full i.i.d. evaluation of each of its seeds; arrays hold one value per seed."""

    label: str
    reference_costs: np.ndarray  # the standard evaluation's total cost
    reference_trials: np.ndarray  # the standard evaluation's done trials
    trials_at_reference: np.ndarray  # this strategy's done trials within that cost
    signed_at_reference: np.ndarray  # estimate within that cost - full value
    signed_at_end: np.ndarray  # estimate over the whole run - full value
    end_cost: float  # where the group's longest run ended
    curve: stats.ErrorCurve

    @property
    def seeds(self) -> int:
        return len(self.reference_costs)

    @property
    def error_at_reference(self) -> float:
        return float(np.mean(np.abs(self.signed_at_reference)))

    @property
    def error_at_end(self) -> float:
        return float(np.mean(np.abs(self.signed_at_end)))


def _versus(label: str, pairs: list[tuple[Run, Run]], metric: str, n_bins: int, top: float) -> VersusFull:
    truths = np.array([stats.full_value(ref.results, metric) for _, ref in pairs])
    ref_costs = np.array([stats.total_cost(ref.results) for _, ref in pairs])
    runs = [run.results for run, _ in pairs]
    at_ref = np.array(
        [stats.running_estimate(df, metric, np.array([c]))[0] for df, c in zip(runs, ref_costs, strict=True)]
    )
    return VersusFull(
        label=label,
        reference_costs=ref_costs,
        reference_trials=np.array([len(stats.done(ref.results)) for _, ref in pairs]),
        trials_at_reference=np.array([stats.trials_at_cost(df, c) for df, c in zip(runs, ref_costs, strict=True)]),
        signed_at_reference=at_ref - truths,
        signed_at_end=np.array([stats.full_value(df, metric) for df in runs]) - truths,
        end_cost=max(stats.total_cost(df) for df in runs),
        curve=stats.error_vs_cost(list(zip(runs, truths, strict=True)), metric, n_bins, top),
    )


def versus_full(groups: list[Group], runs: list[Run], metric: str, n_bins: int = 50) -> list[VersusFull]:
    """Estimation error and trials at the standard evaluation's cost, for every group whose seeds have one.

    All curves share one cost grid: `n_bins` bins up to the largest cost of any run involved."""
    matched = []
    for group in groups:
        pairs = [(run, ref) for run in group.runs if (ref := reference_for(run, runs)) is not None]
        if pairs:
            matched.append((group.label, pairs))
    if not matched:
        return []
    top = max(stats.total_cost(r.results) for _, pairs in matched for pair in pairs for r in pair)
    return [_versus(label, pairs, metric, n_bins, top) for label, pairs in matched]


@dataclass
class Comparison:
    a: Run
    b: Run
    differences: dict[str, stats.Estimate]  # metric -> mean per-trial difference a - b


def comparisons(pairs: list[tuple[Run, Run]]) -> list[Comparison]:
    return [
        Comparison(a, b, {m: stats.paired_difference(a.results, b.results, m, rng()) for m in METRICS})
        for a, b in pairs
    ]


def trials_curves(groups: list[Group], n_bins: int = 50) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, float]]]:
    """Done trials within each budget on a common grid up to the largest run cost: per group, the
    (seeds, bins) counts and where its longest run ended."""
    ends = {g.label: max(stats.total_cost(r.results) for r in g.runs) for g in groups}
    costs = np.concatenate([[0.0], stats.cost_bins(max(max(ends.values()), 1e-9), n_bins)])
    return costs, {
        g.label: (np.array([stats.trials_at_cost(r.results, costs) for r in g.runs]), ends[g.label]) for g in groups
    }


def with_overall(
    table: dict[str, dict[str, stats.Estimate]], groups: list[Group], metric: str
) -> dict[str, dict[str, stats.Estimate]]:
    """`table` with each group's estimate over all its trials first, under "all"."""
    pooled = {g.label: g.pooled for g in groups}
    return {label: {"all": stats.metric_estimate(pooled[label], metric), **per} for label, per in table.items()}
