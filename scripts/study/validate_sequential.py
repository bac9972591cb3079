"""Validity of the sequential statistics on simulated clustered studies (issue 20).

For binary and SPL-like outcomes, 10, 30 and 100 base instances, and success rates near 0.5 and 0.03, it simulates
--studies studies and measures: how often the anytime-valid confidence sequence covers the true mean at every base
(goal >= 95%), how often the fixed-n interval of the report covers it (goal >= 94%; the cluster bootstrap it
replaced alongside), and how often --stop.compare declares two equal policies different at any trial (goal <= 5%).
Then the per-trial time of the stopping machinery (goal: < 1% of a 10 Hz control period).

Each base has 1 to 10 trials (uneven clusters) sharing a success probability drawn from Beta(5r, 5(1 - r)) (the
heterogeneity of tests/test_stats.py); an SPL-like outcome is success times a path efficiency ~ Beta(8, 2).

    .venv/bin/python scripts/study/validate_sequential.py [--studies=1000] [--seed=0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from lerobot_contrast.contrast.confseq import (
    ConfidenceSequence,
    difference_bounds,
    difference_sequence,
    difference_unit,
)
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.stopping import Monitor, StopRule, excludes_zero, trial_key
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.reporting import stats

MOST_TRIALS = 10  # trials of the largest base a plan can have: the bases' weights are relative to it
EFFICIENCY = 0.8  # mean of Beta(8, 2)
ALPHA = 0.05
PERIOD_S = 0.1  # 10 Hz
WIDTH = 0.1  # the --stop.width whose tuned bets the coverage is measured with


def simulate(rng: np.random.Generator, studies: int, bases: int, rate: float, spl: bool):
    """Per study and base: trial counts and two policies' trial values (equal policies: same base difficulty)."""
    p = rng.beta(5 * rate, 5 * (1 - rate), size=(studies, bases))
    sizes = rng.integers(1, MOST_TRIALS + 1, size=(studies, bases))
    trial_p = np.repeat(p.ravel(), sizes.ravel())

    def outcomes():
        success = (rng.random(len(trial_p)) < trial_p).astype(float)
        return success * rng.beta(8.0, 2.0, size=len(trial_p)) if spl else success

    return sizes, outcomes(), outcomes()


def base_means(sizes: np.ndarray, values: np.ndarray) -> np.ndarray:
    sums = np.add.reduceat(values, np.concatenate([[0], np.cumsum(sizes.ravel())[:-1]]))
    return (sums / sizes.ravel()).reshape(sizes.shape)


def sequential_figures(sizes, a, b, truth: float) -> tuple[float, float]:
    """Time-uniform coverage of the headline sequence, and how often the equal-policy comparison is decided."""
    studies, bases = sizes.shape
    mean_a, mean_b = base_means(sizes, a), base_means(sizes, b)
    own = ConfidenceSequence(ALPHA, studies, target_width=WIDTH)  # as the monitor under --stop.width=0.1
    difference = difference_sequence(ALPHA, studies)
    missed = np.zeros(studies, dtype=bool)
    decided = np.zeros(studies, dtype=bool)
    for j in range(bases):
        weight = sizes[:, j] / MOST_TRIALS
        own.update(mean_a[:, j], weight)
        difference.update(difference_unit(mean_a[:, j], mean_b[:, j]))  # as the monitor: every base alike
        missed |= (own.low > truth) | (own.high < truth)
        decided |= excludes_zero(*difference_bounds(difference))
    return 1 - missed.mean(), decided.mean()


def fixed_n_coverage(sizes, values, truth: float, rng: np.random.Generator) -> tuple[float, float]:
    """Coverage of the report's interval (Korn-Graubard) and of the cluster bootstrap it replaced."""
    starts = np.concatenate([[0], np.cumsum(sizes.sum(axis=1))])
    covered = np.zeros((2, len(sizes)), dtype=bool)
    for s, row in enumerate(sizes):
        v, clusters = values[starts[s] : starts[s + 1]], np.repeat(np.arange(len(row)), row)
        for m, e in enumerate((stats.estimate(v, clusters), stats.bootstrap_estimate(v, clusters, rng, 1000))):
            covered[m, s] = e.low <= truth <= e.high
    return covered[0].mean(), covered[1].mean()


def overhead_per_trial(rng: np.random.Generator, bases: int = 100, per_base: int = 7) -> float:
    """Seconds the stopping machinery spends per trial of a run with --stop.width and --stop.compare."""
    scene = Scene(objects={})
    plan, records = [], []
    for j in range(bases):
        base = Instance(id=f"b{j}", family="f", instruction="go", scene=scene)
        for k in range(per_base):
            index, name = len(plan), None if k == 0 else f"P{k}"
            plan.append(PlannedTrial(index, base, name, "reset"))
            success = bool(rng.random() < 0.5)
            records.append(
                TrialRecord(index, base.id, name, None, "f", "reset", 0, "done", base, 0.0, 0.0, success, None, 0.0)
            )
    reference = {trial_key(r): float(rng.random() < 0.5) for r in records}
    monitor = Monitor(plan, StopRule(width=1e-9, alpha=ALPHA, reference=reference, reference_name="ref"))
    start = time.perf_counter()
    for record in records:
        monitor.observe(record)
        monitor.line()
    return (time.perf_counter() - start) / len(records)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--studies", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    figures: dict[str, float] = {}
    print(f"{'outcome':<8}{'bases':>6}{'rate':>6}{'CS cover':>10}{'fixed-n':>9}{'bootstrap':>10}{'compare FP':>11}")
    for spl in (False, True):
        for bases in (10, 30, 100):
            for rate in (0.5, 0.03):
                sizes, a, b = simulate(rng, args.studies, bases, rate, spl)
                truth = rate * EFFICIENCY if spl else rate
                cs_cover, false_positive = sequential_figures(sizes, a, b, truth)
                fixed, bootstrap = fixed_n_coverage(sizes, a, truth, rng)
                name = f"{'spl' if spl else 'binary'}_{bases}_{rate:g}"
                figures |= {f"cs_{name}": cs_cover, f"fixed_{name}": fixed, f"fp_{name}": false_positive}
                outcome = "spl" if spl else "binary"
                print(
                    f"{outcome:<8}{bases:>6}{rate:>6g}{cs_cover:>10.3f}{fixed:>9.3f}{bootstrap:>10.3f}"
                    f"{false_positive:>11.3f}"
                )
    per_trial = overhead_per_trial(rng)
    worst = {
        "cs_coverage_min": min(v for k, v in figures.items() if k.startswith("cs_")),
        "fixed_coverage_min": min(v for k, v in figures.items() if k.startswith("fixed_")),
        "compare_fp_max": max(v for k, v in figures.items() if k.startswith("fp_")),
        "overhead_ms_per_trial": per_trial * 1e3,
        "overhead_pct_of_10hz_period": 100 * per_trial / PERIOD_S,
    }
    print(" ".join(f"{k}={v:.4g}" for k, v in {"studies": args.studies, **worst, **figures}.items()))


if __name__ == "__main__":
    main()
