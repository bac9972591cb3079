"""Coverage and width of the audited estimates (contrast/audited.py) over simulated sessions, where the camera's
mistakes are known: a contrast set of `--bases` bases, each an original and four perturbations whose true success
rates differ, labelled by a camera that errs at 0, 2, 5 or 10 %, evenly (either way), toward success (failures called
successes), or on one perturbation only; a random 5, 10 or 20 % of trials audited by a person who is right.

    .venv/bin/python scripts/bench/bench_audit.py [--sessions=4000] [--bases=60] [--seed=0]

Prints each setting's coverage of the 95% intervals (success rate, and the paired change of the perturbation the
skewed camera errs on), audited and camera-only, and the widths against the camera-only and all-person intervals;
then on its last line: coverage_min=... coverage_max=... (audited, over every labeller, audit share and estimate)
camera_only_coverage_min=... width_ratio_camera_<share>=... width_ratio_person_<share>=... (mean width of the audited
rate's interval over the camera-only one, and over the all-person one, with a 2 % even labeller), then per audit
share coverage_max_<share>=... and least_coverage_max_<share>=...

The least coverage_max is what any interval must cover where the camera is never wrong, if it is centred on the
camera's estimate wherever the audit saw no disagreement (all the audit can tell there) and covers 0.94 with every
labeller simulated: a camera that errs one way goes unseen by a small audit in a share P0 of sessions, where its
estimate is off by B of its standard errors; with every other session covered, the interval must be K standard
errors wide with P0 (Phi(K - B) - Phi(-K - B)) + 1 - P0 = 0.94, and where the camera is right that covers
2 Phi(K) - 1. A coverage_max above 0.96 is then the audit's size, not the method.
"""

from __future__ import annotations

import argparse
import itertools

import numpy as np
from scipy.optimize import brentq
from scipy.stats import norm

from lerobot_contrast.contrast import audited
from lerobot_contrast.contrast.intervals import t_quantile

PERTURBATIONS = ("L", "LB", "S", "SB")
SHIFT = {"L": 0.0, "LB": -0.3, "S": -0.05, "SB": -0.2}  # each perturbation's change of the true success rate
ERRORS = (0.0, 0.02, 0.05, 0.10)
SKEWS = ("even", "to_success", "on_S")
SHARES = (0.05, 0.10, 0.20)
TRUTH_BASES = 2_000_000


def base_rates(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 5) true success probabilities: each base's own, then shifted per perturbation."""
    own = rng.beta(3, 2, n)[:, None]
    return np.clip(own + np.array([0.0, *(SHIFT[p] for p in PERTURBATIONS)]), 0, 1)


def camera(truth: np.ndarray, error: float, skew: str, rng: np.random.Generator) -> np.ndarray:
    """The camera's labels of (bases, 5) true outcomes."""
    flip = rng.random(truth.shape)
    if skew == "even":
        wrong = flip < error
    elif skew == "to_success":
        wrong = (truth == 0) & (flip < 2 * error)
    else:  # every mistake on the S trials, failures called successes
        wrong = np.zeros(truth.shape, bool)
        s = 1 + PERTURBATIONS.index("S")
        wrong[:, s] = (truth[:, s] == 0) & (flip[:, s] < 10 * error)
    return np.where(wrong, 1 - truth, truth)


def clustered_t(values: np.ndarray) -> tuple[float, float]:
    """A (bases, k) table's mean with its clustered t interval (bases as clusters, equal sizes)."""
    per_base = values.mean(axis=1)
    half = t_quantile(len(per_base) - 1) * per_base.std(ddof=1) / np.sqrt(len(per_base))
    return per_base.mean() - half, per_base.mean() + half


def session(rng, bases, error, skew, share):
    """One session's intervals, {estimate: (low, high)} for the audited, camera-only and all-person estimates, and
    {estimate: whether the audit saw the camera err on its trials}."""
    truth = (rng.random((bases, 5)) < base_rates(rng, bases)).astype(float)
    said = camera(truth, error, skew, rng)
    audit = rng.random(truth.shape) < share
    ids = np.repeat(np.arange(bases), 5)
    out = {}
    rate = audited.rate(said.ravel(), audit.ravel(), truth.ravel(), ids)
    out["rate"] = (rate.low, rate.high)
    out["rate_camera"] = clustered_t(said)
    out["rate_person"] = clustered_t(truth)
    s = 1 + PERTURBATIONS.index("S")
    pair = np.stack([said[:, 0], said[:, s]], axis=1)
    change = audited.paired_change(pair.ravel(), np.stack([audit[:, 0], audit[:, s]], 1).ravel(),
                                   np.stack([truth[:, 0], truth[:, s]], 1).ravel(), np.repeat(np.arange(bases), 2),
                                   np.tile([False, True], bases))  # fmt: skip
    out["change"] = (change.low, change.high)
    out["change_camera"] = clustered_t((pair[:, 1] - pair[:, 0])[:, None])
    seen = audit & (said != truth)
    return out, {"rate": bool(seen.any()), "change": bool(seen[:, [0, s]].any())}


def least_coverage_max(unseen: float, bias: float) -> float:
    """The coverage where the camera is right of the narrowest interval that covers 0.94 where a camera off by
    `bias` standard errors goes unseen in a share `unseen` of sessions (module docstring)."""
    need = 1 - (1 - 0.94) / unseen if unseen > 0 else 0.0  # coverage needed of the unseen sessions
    if need <= 0:
        return 0.0
    covered = lambda k: norm.cdf(k - bias) - norm.cdf(-k - bias) - need  # noqa: E731
    return float(2 * norm.cdf(brentq(covered, 0.0, 50.0)) - 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sessions", type=int, default=4000)
    parser.add_argument("--bases", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rates = base_rates(np.random.default_rng(args.seed), TRUTH_BASES)
    truth = {"rate": rates.mean(), "change": (rates[:, 1 + PERTURBATIONS.index("S")] - rates[:, 0]).mean()}
    rng = np.random.default_rng(args.seed + 1)
    covered, camera_covered, widths = [], [], {}
    by_share = {share: {"coverage": [], "least": [0.0]} for share in SHARES}
    print(f"{'camera error':>12} {'skew':>10} {'audit':>5}  rate: audited camera-only unseen  "
          f"change: audited camera-only unseen")  # fmt: skip
    for error, skew, share in itertools.product(ERRORS, SKEWS, SHARES):
        if error == 0 and skew != "even":
            continue
        runs, seen = zip(*(session(rng, args.bases, error, skew, share) for _ in range(args.sessions)), strict=True)
        cover = {k: np.mean([low <= truth[k.split("_")[0]] <= high for low, high in (r[k] for r in runs)])
                 for k in runs[0]}  # fmt: skip
        unseen = {k: 1 - np.mean([s[k] for s in seen]) for k in truth}
        for k in truth:  # the camera's bias where the audit saw no mistake, in its standard errors
            camera_mid = np.array([sum(r[f"{k}_camera"]) / 2 for r, s in zip(runs, seen, strict=True) if not s[k]])
            bias = abs(camera_mid.mean() - truth[k]) / camera_mid.std() if len(camera_mid) > 1 else 0.0
            by_share[share]["least"].append(least_coverage_max(unseen[k], bias) if error > 0 else 0.0)
        covered += [cover["rate"], cover["change"]]
        by_share[share]["coverage"] += [cover["rate"], cover["change"]]
        camera_covered += [cover["rate_camera"], cover["change_camera"]]
        if error == 0.02 and skew == "even":
            width = {k: np.mean([high - low for low, high in (r[k] for r in runs)]) for k in runs[0]}
            widths[f"width_ratio_camera_{share:g}"] = width["rate"] / width["rate_camera"]
            widths[f"width_ratio_person_{share:g}"] = width["rate"] / width["rate_person"]
        print(f"{error:>12.2f} {skew:>10} {share:>5.2f}  {cover['rate']:>13.3f} {cover['rate_camera']:>11.3f} "
              f"{unseen['rate']:>6.2f}  {cover['change']:>15.3f} {cover['change_camera']:>11.3f} "
              f"{unseen['change']:>6.2f}")  # fmt: skip
    figures = {
        "coverage_min": min(covered),
        "coverage_max": max(covered),
        "camera_only_coverage_min": min(camera_covered),
        **widths,
    }
    for share, got in by_share.items():
        figures[f"coverage_max_{share:g}"] = max(got["coverage"])
        figures[f"least_coverage_max_{share:g}"] = max(got["least"])
    print(" ".join(f"{k}={v:.3f}" for k, v in figures.items()))


if __name__ == "__main__":
    main()
