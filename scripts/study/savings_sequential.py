"""Savings of the sequential rules (issue 20), resampling the base instances of finished runs of one plan.

Given a complete contrast run of policy A and one of policy B on the same plan (for example the learned default and
the oracle, or the learned default and its copy with --policy.noise_std), it draws --studies streams of bases with
replacement (each base with its trials, their staging cost and B's paired trials) and measures:
- width: the cost until the anytime-valid interval of A's headline metric is --width wide (--stop.width), against
  two fixed budgets of today's contrast strategy: the number of bases that guarantees that width whatever the
  outcomes (every base's mean in [0, 1], so a variance of at most 1/4 per base: the budget a user can plan without
  knowing the variance), and the number at which the fixed-n (Korn-Graubard) interval is that wide in half of the
  studies (known only in hindsight; no rule that may stop at any time can beat it);
- compare: A's trials until --stop.compare decides A against B at --alpha, open-ended and within a plan as long as
  the runs, against the trials of the smallest fixed-n cluster-robust paired t-test (two-sided, at --alpha) with at
  least the same power; and the fewest bases any betting test needs on average, log(2/alpha) over the growth rate of
  the best constant bet on these bases' differences (Wald's identity): the floor that bounded outcomes set;
- the per-perturbation means' mean absolute error at the width stop and at the fixed n, against all of A's bases.

    .venv/bin/python scripts/study/savings_sequential.py RUN_A RUN_B [--width=0.1] [--alpha=0.05] [--studies=1000]
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.confseq import (
    ConfidenceSequence,
    difference_bounds,
    difference_sequence,
    difference_unit,
)
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
    unit = difference_unit(*base_pairs(own, paired))
    cs = difference_sequence(alpha, len(draws))
    stop = np.full(len(draws), -1)
    for m in range(draws.shape[1]):
        picked = draws[:, m]
        cs.update(unit[picked])  # as the monitor: every base alike
        stop = np.where((stop < 0) & excludes_zero(*difference_bounds(cs)), m, stop)
    return np.where(stop >= 0, stop + 1, np.nan)


def base_pairs(own, paired):
    """Per base: A's and B's mean over the trials both ran (NaN where they share none)."""
    both = ~np.isnan(own) & ~np.isnan(paired)
    counts = np.where(both.any(axis=1), both.sum(axis=1), np.nan)
    return np.where(both, own, 0.0).sum(axis=1) / counts, np.where(both, paired, 0.0).sum(axis=1) / counts


def fixed_power(own, paired, draws, n, alpha):
    """Power of the fixed-n paired test on n bases: the mean difference over trials, cluster-robust t with k-1
    degrees of freedom, two-sided at `alpha` (as the sequence is)."""
    both = ~np.isnan(own) & ~np.isnan(paired)
    diff_sum, counts = np.where(both, own - paired, 0.0).sum(axis=1), both.sum(axis=1).astype(float)
    s, c = diff_sum[draws[:, :n]], counts[draws[:, :n]]
    mean = s.sum(axis=1) / c.sum(axis=1)
    variance = n / (n - 1) * ((s - mean[:, None] * c) ** 2).sum(axis=1) / c.sum(axis=1) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.abs(mean) / np.sqrt(variance)
    return float(np.mean(np.where(variance > 0, t > t_quantile(n - 1, 1 - alpha), mean != 0)))


def fixed_bases_at_power(own, paired, draws, power, alpha, most=500):
    """The fewest bases whose fixed-n test has at least `power` (NaN: none up to `most`)."""
    if power <= 0:
        return float("nan")
    return next((n for n in range(3, most + 1) if fixed_power(own, paired, draws, n, alpha) >= power), float("nan"))


def best_bet_bases(own, paired, alpha):
    """log(2/alpha) over the growth rate E log(1 + bet * d) of the best constant bet on the bases' mean differences d:
    by Wald's identity, the fewest bases a hedged betting test at `alpha` needs on average, even knowing that bet."""
    a, b = base_pairs(own, paired)
    d = (a - b)[~np.isnan(a - b)]
    bets = np.linspace(-0.999, 0.999, 1999)
    growth = np.log1p(bets[:, None] * d[None, :]).mean(axis=1).max()
    return float(np.log(2 / alpha) / growth) if growth > 0 else float("inf")


def compare_figures(own, paired, draws, alpha, per_base):
    """Open-ended (the test runs until decided) and within a plan of as many bases as the runs have."""
    decided = compare_stop(own, paired, draws, alpha)
    horizon = len(own)
    power = float(np.mean(~np.isnan(decided)))
    in_plan = np.fmin(np.nan_to_num(decided, nan=horizon), horizon)
    power_plan = float(np.mean(decided <= horizon))
    n_fixed = fixed_bases_at_power(own, paired, draws, power, alpha)
    n_fixed_plan = fixed_bases_at_power(own, paired, draws, power_plan, alpha)
    return {
        "compare_power_seq": power,
        "compare_seq_mean_trials": float(np.nanmean(decided)) * per_base,
        "compare_fixed_trials": n_fixed * per_base,
        "compare_trial_saving": 1 - float(np.nanmean(decided)) / n_fixed,
        "compare_best_bet_trials": best_bet_bases(own, paired, alpha) * per_base,
        "compare_plan_bases": horizon,
        "compare_plan_power_seq": power_plan,
        "compare_plan_seq_mean_trials": float(in_plan.mean()) * per_base,
        "compare_plan_fixed_trials": n_fixed_plan * per_base,
        "compare_plan_trial_saving": 1 - float(in_plan.mean()) / n_fixed_plan,
    }


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
    parser.add_argument("--studies", type=int, default=1000)
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
    # Guaranteed whatever the outcomes: a base's mean lies in [0, 1], so its variance is at most 1/4 and
    # 2 z sqrt(1/4 / n) <= width at n = (z / width)^2 bases.
    guaranteed_bases = np.ceil((t_quantile(np.inf, 1 - args.alpha) / args.width) ** 2)
    guaranteed_cost = float(guaranteed_bases * cost.mean())
    seq_cost = float(np.nanmedian(cost_seq))
    figures = {
        "metric": metric,
        "bases_in_runs": len(own),
        "width": args.width,
        "width_decided_share": float(np.mean(~np.isnan(cost_seq))),
        "width_seq_median_cost": seq_cost,
        "width_guaranteed_plan_bases": int(guaranteed_bases),
        "width_guaranteed_plan_cost": guaranteed_cost,
        "width_cost_saving_vs_guaranteed_plan": 1 - seq_cost / guaranteed_cost,
        "width_hindsight_fixed_bases": n_fixed,
        "width_hindsight_fixed_cost": cost_fixed,
        "width_cost_saving_vs_hindsight": 1 - seq_cost / cost_fixed,
        "width_seq_pert_abs_err": perturbation_error(own, draws, bases_seq),
        "width_fixed_pert_abs_err": perturbation_error(own, draws, np.full(len(draws), n_fixed or np.nan)),
        **compare_figures(own, paired, draws[:, :500], args.alpha, per_base),
        "seconds": time.perf_counter() - start,
    }
    print(f"perturbations: {', '.join(names)}")
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in figures.items()))


if __name__ == "__main__":
    main()
