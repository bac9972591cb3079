"""Statistics of a run: mean metrics with 95% intervals clustered by base instance, paired sensitivities,
estimation error against the full i.i.d. evaluation as a function of cost, and trials per unit cost.

Every function takes the results table as a DataFrame (see `frame`); only trials with status "done" count.
"""

from __future__ import annotations

import typing
import warnings
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pyarrow as pa
from scipy import stats as distributions

from lerobot_contrast.contrast.intervals import korn_graubard, t_quantile
from lerobot_contrast.contrast.trial import Status, TrialRecord
from lerobot_contrast.record.results import SCHEMA, record_row

STATUSES: tuple[Status, ...] = typing.get_args(Status)
CONFIDENCE = 0.95
N_BOOT = 2000
Z95 = float(distributions.norm.ppf(0.5 + CONFIDENCE / 2))


@dataclass(frozen=True)
class Estimate:
    """A mean with its interval. `method`: korn_graubard (see `estimate`) or cluster_bootstrap (differences)."""

    mean: float
    low: float
    high: float
    n_trials: int
    n_clusters: int
    method: str


def frame(source: Iterable[TrialRecord] | pd.DataFrame | pa.Table) -> pd.DataFrame:
    """The results table as a DataFrame, from journal records, a results.parquet table or a DataFrame."""
    if isinstance(source, pa.Table):
        return source.to_pandas()
    if isinstance(source, pd.DataFrame):
        return source
    return pa.Table.from_pylist([record_row(r) for r in source], schema=SCHEMA).to_pandas()


def done(df: pd.DataFrame) -> pd.DataFrame:
    return df[df["status"] == "done"]


def status_counts(df: pd.DataFrame) -> dict[str, int]:
    counts = df["status"].value_counts()
    return {status: int(counts.get(status, 0)) for status in STATUSES}


def metric_values(df: pd.DataFrame, metric: str) -> pd.DataFrame:
    """Done trials with a value for `metric`, as columns base_id and value (floats; success as 0/1)."""
    rows = done(df)
    values = rows[metric].astype("float64")
    keep = values.notna()
    return pd.DataFrame({"base_id": rows["base_id"][keep].to_numpy(), "value": values[keep].to_numpy()})


def cluster_sums(values: np.ndarray, clusters: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-cluster sum of values and number of trials."""
    _, inverse = np.unique(clusters, return_inverse=True)
    return np.bincount(inverse, weights=values), np.bincount(inverse).astype(np.float64)


def bootstrap_means(sums: np.ndarray, sizes: np.ndarray, rng: np.random.Generator, n_boot: int = N_BOOT) -> np.ndarray:
    """Means over all trials of `n_boot` resamples of whole clusters (drawn with replacement)."""
    pick = rng.integers(len(sums), size=(n_boot, len(sums)))
    return sums[pick].sum(axis=1) / sizes[pick].sum(axis=1)


def bootstrap_interval(draws: np.ndarray, mean: float, n_clusters: int) -> tuple[float, float]:
    """Percentile interval of the bootstrap means, widened about the mean for few clusters.

    The bootstrap spread is that of a mean over k clusters with variance divided by k, not k - 1, and normal
    rather than t tails, so its intervals undercover with tens of clusters. Scaling the draws by
    sqrt(k / (k - 1)) * t_{k-1} / z is the small-sample correction clustered standard errors use.
    """
    if n_clusters < 2:
        return (float("nan"), float("nan"))
    widen = np.sqrt(n_clusters / (n_clusters - 1)) * t_quantile(n_clusters - 1) / Z95
    tail = (1 - CONFIDENCE) / 2
    low, high = mean + (np.quantile(draws, [tail, 1 - tail]) - mean) * widen
    return (float(low), float(high))


def bootstrap_estimate(
    values: np.ndarray, clusters: np.ndarray, rng: np.random.Generator, n_boot: int = N_BOOT
) -> Estimate:
    """The mean over trials with a 95% interval from resampling whole clusters (see `bootstrap_interval`)."""
    values = np.asarray(values, dtype=np.float64)
    if len(values) == 0:
        return Estimate(float("nan"), float("nan"), float("nan"), 0, 0, "none")
    sums, sizes = cluster_sums(values, np.asarray(clusters))
    mean = float(values.mean())
    low, high = bootstrap_interval(bootstrap_means(sums, sizes, rng, n_boot), mean, len(sums))
    # Widening must not carry the interval past values a mean of these trials can take.
    low, high = max(low, float(values.min())), min(high, float(values.max()))
    return Estimate(mean, low, high, len(values), len(sums), "cluster_bootstrap")


def estimate(values: np.ndarray, clusters: np.ndarray) -> Estimate:
    """The mean over trials with a 95% interval that respects clustering by base instance (`korn_graubard`).

    Unlike the cluster bootstrap it replaced, it keeps its coverage near rates of 0 and 1 with tens of uneven
    bases (scripts/study/validate_sequential.py measures both).
    """
    values, clusters = np.asarray(values, dtype=np.float64), np.asarray(clusters)
    if len(values) == 0:
        return Estimate(float("nan"), float("nan"), float("nan"), 0, 0, "none")
    low, high = korn_graubard(*cluster_sums(values, clusters), CONFIDENCE)
    return Estimate(float(values.mean()), low, high, len(values), len(np.unique(clusters)), "korn_graubard")


def metric_estimate(df: pd.DataFrame, metric: str) -> Estimate:
    rows = metric_values(df, metric)
    return estimate(rows["value"].to_numpy(), rows["base_id"].to_numpy())


def grouped_estimates(df: pd.DataFrame, by: str, metric: str) -> dict[str, Estimate]:
    """`metric_estimate` per value of column `by` (perturbation: None reads "original"; family)."""
    keys = df[by].fillna("original") if by == "perturbation" else df[by]
    return {str(name): metric_estimate(group, metric) for name, group in df.groupby(keys, sort=False)}


def paired_sensitivity(df: pd.DataFrame, metric: str, rng: np.random.Generator) -> dict[str, Estimate]:
    """Per perturbation: mean over bases of (its perturbed metric - the same base's original metric).

    Repeats are averaged within a base first; the interval resamples bases. Bases where either side has no
    done trial are left out.
    """
    rows = done(df).sort_values("index")
    rows = rows.assign(value=rows[metric].astype("float64"), perturbation=rows["perturbation"].fillna("original"))
    per_base = rows.dropna(subset=["value"]).groupby(["perturbation", "base_id"])["value"].mean()
    if "original" not in per_base.index.get_level_values(0):
        return {}
    original = per_base.loc["original"]
    out = {}
    for name in pd.unique(rows["perturbation"]):
        if name == "original" or name not in per_base.index.get_level_values(0):
            continue
        diff = (per_base.loc[name] - original).dropna().to_numpy()
        out[name] = bootstrap_estimate(diff, np.arange(len(diff)), rng)
    return out


def paired_difference(a: pd.DataFrame, b: pd.DataFrame, metric: str, rng: np.random.Generator) -> Estimate:
    """Mean per-trial difference a - b over trials of the same instance id and repeat that are done in both,
    with a cluster bootstrap interval over base instances."""
    keys = ["instance_id", "repeat"]
    left = done(a)[[*keys, "base_id", metric]]
    right = done(b)[[*keys, metric]]
    both = left.merge(right, on=keys, suffixes=("_a", "_b")).dropna(subset=[f"{metric}_a", f"{metric}_b"])
    diff = both[f"{metric}_a"].astype("float64") - both[f"{metric}_b"].astype("float64")
    return bootstrap_estimate(diff.to_numpy(), both["base_id"].to_numpy(), rng)


def _ordered(df: pd.DataFrame, metric: str | None = None) -> pd.DataFrame:
    rows = done(df).sort_values("index")
    if metric is not None:
        rows = rows[rows[metric].astype("float64").notna()]
    return rows


def running_estimate(df: pd.DataFrame, metric: str, costs: np.ndarray) -> np.ndarray:
    """The mean metric over the trials affordable with each budget in `costs` (cumulative cost <= budget);
    NaN before the first trial. A budget beyond the run's total cost holds the final estimate."""
    rows = _ordered(df, metric)
    values = rows[metric].astype("float64").to_numpy()
    running = np.cumsum(values) / np.arange(1, len(values) + 1)
    count = np.searchsorted(rows["cumulative_cost"].to_numpy(), costs, side="right")
    return np.where(count > 0, running[np.maximum(count - 1, 0)] if len(values) else np.nan, np.nan)


def trials_at_cost(df: pd.DataFrame, costs: np.ndarray | float) -> np.ndarray:
    """Done trials whose cumulative cost is within each budget."""
    return np.searchsorted(_ordered(df)["cumulative_cost"].to_numpy(), costs, side="right")


def total_cost(df: pd.DataFrame) -> float:
    rows = _ordered(df)
    return float(rows["cumulative_cost"].iloc[-1]) if len(rows) else 0.0


def trials_per_unit_cost(df: pd.DataFrame) -> float:
    cost = total_cost(df)
    return len(done(df)) / cost if cost > 0 else float("nan")


def full_value(standard: pd.DataFrame, metric: str) -> float:
    """The full i.i.d. value: the metric's mean over a complete, unbudgeted standard evaluation."""
    return float(metric_values(standard, metric)["value"].mean())


@dataclass(frozen=True)
class ErrorCurve:
    """|estimate - full i.i.d. value| against cost: per-bin mean and standard deviation over seeds."""

    costs: np.ndarray  # right edge of each bin
    mean: np.ndarray
    std: np.ndarray
    errors: np.ndarray  # (seeds, bins)


def cost_bins(max_cost: float, n_bins: int = 50) -> np.ndarray:
    """The paper's grid: `n_bins` equal-width bins from 0 to `max_cost`, as their right edges."""
    return np.linspace(0.0, max_cost, n_bins + 1)[1:]


def error_vs_cost(
    runs: list[tuple[pd.DataFrame, float]], metric: str, n_bins: int = 50, max_cost: float | None = None
) -> ErrorCurve:
    """The paper's estimation error curve over seeds: one (run, full i.i.d. value of its seed) per seed.

    Bins span 0 to `max_cost` (default: the largest cost across the runs); the std is over seeds (ddof=1).
    """
    top = max(total_cost(df) for df, _ in runs) if max_cost is None else max_cost
    costs = cost_bins(top, n_bins)
    errors = np.array([np.abs(running_estimate(df, metric, costs) - truth) for df, truth in runs])
    with warnings.catch_warnings():  # bins before any seed's first trial are all-NaN, and stay NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(errors, axis=0)
        std = np.nanstd(errors, axis=0, ddof=1) if len(runs) > 1 else np.full(len(costs), np.nan)
    return ErrorCurve(costs, mean, std, errors)
