"""Savings of the sequential rules (issue 20), resampling the base instances of finished runs of one plan.

Given a complete contrast run of policy A and one of policy B on the same plan (for example the learned default and
the oracle), it draws --studies streams of bases with replacement (each base with its trials, their staging cost and
B's paired trials) and measures:
- width: the cost until the anytime-valid interval of A's headline metric is --width wide (--stop.width), against
  the cost of the fixed number of bases at which the fixed-n (Korn-Graubard) interval is that wide in half of the
  studies (a number only known in hindsight), and of the number planned without knowing the variance (independent
  trials at p = 1/2);
- compare: A's trials until --stop.compare decides A against B at --alpha, against the trials of the smallest
  fixed-n cluster-robust paired t-test with at least the same power;
- the per-perturbation means' mean absolute error at the width stop and at the fixed n, against all of A's bases.

    .venv/bin/python scripts/savings_sequential.py RUN_A RUN_B [--width=0.1] [--alpha=0.05] [--studies=200]
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.confseq import ConfidenceSequence, difference_bounds, difference_unit
from lerobot_contrast.contrast.intervals import korn_graubard, t_quantile
from lerobot_contrast.contrast.stopping import excludes_zero, headline_metric, headline_value, trial_key
from lerobot_contrast.record.journal import read_journal


def tables(run_a: Path, run_b: Path):
    """Per base of A (plan order): A's value per perturbation, B's paired value, and the staging cost A paid."""
    a, b = read_journal(run_a / "journal.jsonl"), read_journal(run_b / "journal.jsonl")
    metric = headline_metric(a)
    other = {trial_key(r): headline_value(r, metric) for r in b}
    bases = list(dict.fromkeys(r.base_id for r in a))
    names = list(dict.fromkeys(r.perturbation or "original" for r in a))
    own, paired = np.full((len(bases), len(names)), np.nan), np.full((len(bases), len(names)), np.nan)
    cost = np.zeros(len(bases))
    for r in a:
        j, p = bases.index(r.base_id), names.index(r.perturbation or "original")
        cost[j] += r.cost
        value, theirs = headline_value(r, metric), other.get(trial_key(r))
        if value is not None:
            own[j, p] = value
            if theirs is not None:
                paired[j, p] = theirs
    return metric, names, own, paired, cost


def width_stop(own, cost, draws, width, alpha):
    """Per study: bases and cost until the anytime-valid interval is `width` wide (NaN: not within the draws)."""
    sizes = np.sum(~np.isnan(own), axis=1)
    means = np.nanmean(np.where(sizes[:, None] > 0, own, 0.0), axis=1)
    cs = ConfidenceSequence(alpha, len(draws), target_width=width)  # as the monitor under --stop.width
    stop = np.full(len(draws), -1)
    for m in range(draws.shape[1]):
        picked = draws[:, m]
        cs.update(np.where(sizes[picked] > 0, means[picked], np.nan), sizes[picked] / sizes.max())
        stop = np.where((stop < 0) & (cs.high - cs.low <= width), m, stop)
    spent = np.cumsum(cost[draws], axis=1)
    return np.where(stop >= 0, stop + 1, np.nan), np.where(stop >= 0, spent[np.arange(len(draws)), stop], np.nan)


def fixed_width_bases(own, draws, width, alpha, grid):
    """The smallest n in `grid` at which the fixed-n interval is at most `width` wide in half of the studies."""
    sizes = np.sum(~np.isnan(own), axis=1)
    sums = np.nansum(own, axis=1)
    for n in grid:
        widths = []
        for row in draws[:, :n]:
            keep = sizes[row] > 0
            low, high = korn_graubard(sums[row][keep], sizes[row][keep].astype(float), 1 - alpha)
            widths.append(high - low)
        if np.median(widths) <= width:
            return int(n)
    return None


def compare_stop(own, paired, draws, alpha):
    """Per study: bases until the sequential comparison is decided (NaN: undecided within the draws)."""
    both = ~np.isnan(own) & ~np.isnan(paired)
    counts = both.sum(axis=1)
    unit = np.nanmean(np.where(both, difference_unit(np.nan_to_num(own), np.nan_to_num(paired)), np.nan), axis=1)
    cs = ConfidenceSequence(alpha, len(draws))
    stop = np.full(len(draws), -1)
    for m in range(draws.shape[1]):
        picked = draws[:, m]
        cs.update(np.where(counts[picked] > 0, unit[picked], np.nan))  # as the monitor: every base alike
        stop = np.where((stop < 0) & excludes_zero(*difference_bounds(cs)), m, stop)
    return np.where(stop >= 0, stop + 1, np.nan)


def fixed_power(own, paired, draws, n, alpha):
    """Power of the fixed-n paired test on n bases: the mean difference over trials, cluster-robust t, k-1 df."""
    both = ~np.isnan(own) & ~np.isnan(paired)
    diff_sum, counts = np.where(both, own - paired, 0.0).sum(axis=1), both.sum(axis=1).astype(float)
    s, c = diff_sum[draws[:, :n]], counts[draws[:, :n]]
    mean = s.sum(axis=1) / c.sum(axis=1)
    variance = n / (n - 1) * ((s - mean[:, None] * c) ** 2).sum(axis=1) / c.sum(axis=1) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.abs(mean) / np.sqrt(variance)
    return float(np.mean(np.where(variance > 0, t > t_quantile(n - 1, 1 - alpha), mean != 0)))


def perturbation_error(own, draws, n_bases):
    """Mean over studies and perturbations of |per-perturbation mean over the first n bases - over all bases|."""
    truth = np.nanmean(own, axis=0)
    errors = []
    for row, n in zip(draws, n_bases, strict=True):
        if np.isnan(n):
            continue
        with warnings.catch_warnings():  # a perturbation none of the first n bases ran: NaN, left out
            warnings.simplefilter("ignore", RuntimeWarning)
            estimate = np.nanmean(own[row[: int(n)]], axis=0)
        errors.append(np.nanmean(np.abs(estimate - truth)))
    return float(np.mean(errors))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_a", type=Path)
    parser.add_argument("run_b", type=Path)
    parser.add_argument("--width", type=float, default=0.1)
    parser.add_argument("--alpha", type=float, default=0.05)
    parser.add_argument("--studies", type=int, default=200)
    parser.add_argument("--max_bases", type=int, default=1500)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    start = time.perf_counter()
    metric, names, own, paired, cost = tables(args.run_a, args.run_b)
    per_base = float(np.mean(np.sum(~np.isnan(own), axis=1)))
    rng = np.random.default_rng(args.seed)
    draws = rng.integers(len(own), size=(args.studies, args.max_bases))
    bases_seq, cost_seq = width_stop(own, cost, draws, args.width, args.alpha)
    grid = np.unique(np.linspace(10, args.max_bases, 60).astype(int))
    n_fixed = fixed_width_bases(own, draws[: min(args.studies, 100)], args.width, args.alpha, grid)
    cost_fixed = float(np.mean(np.cumsum(cost[draws], axis=1)[:, n_fixed - 1])) if n_fixed else float("nan")
    decided = compare_stop(own, paired, draws[:, :500], args.alpha)
    power_seq = float(np.mean(~np.isnan(decided)))
    powered = (n for n in range(3, 501) if fixed_power(own, paired, draws, n, args.alpha) >= power_seq)
    n_compare = next(powered, float("nan")) if power_seq > 0 else float("nan")
    # Planned without knowing the variance: independent trials at the worst case p = 1/2, n = (z / width)^2.
    worst_bases = np.ceil(t_quantile(np.inf, 1 - args.alpha) ** 2 / args.width**2 / per_base)
    worst_cost = float(worst_bases * cost.mean())
    figures = {
        "metric": metric,
        "bases_in_runs": len(own),
        "width": args.width,
        "width_decided_share": float(np.mean(~np.isnan(cost_seq))),
        "width_seq_median_cost": float(np.nanmedian(cost_seq)),
        "width_fixed_n_bases": n_fixed,
        "width_fixed_cost": cost_fixed,
        "width_cost_saving": 1 - float(np.nanmedian(cost_seq)) / cost_fixed,
        "width_worstcase_plan_cost": worst_cost,
        "width_cost_saving_vs_worstcase_plan": 1 - float(np.nanmedian(cost_seq)) / worst_cost,
        "width_seq_pert_abs_err": perturbation_error(own, draws, bases_seq),
        "width_fixed_pert_abs_err": perturbation_error(own, draws, np.full(len(draws), n_fixed or np.nan)),
        "compare_power_seq": power_seq,
        "compare_seq_mean_trials": float(np.nanmean(decided)) * per_base,
        "compare_fixed_trials": n_compare * per_base,
        "compare_trial_saving": 1 - float(np.nanmean(decided)) / n_compare,
        "seconds": time.perf_counter() - start,
    }
    print(f"perturbations: {', '.join(names)}")
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in figures.items()))


if __name__ == "__main__":
    main()
