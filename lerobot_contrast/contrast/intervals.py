"""Fixed-n intervals for a mean in [0, 1] clustered by base instance: Korn and Graubard's effective-sample-size
Clopper-Pearson interval (the report's, and the live console's fixed-n interval). SciPy loads on the first interval,
so a command that only checks its flags does not wait for it."""

from __future__ import annotations

import numpy as np


def t_quantile(dof: float, confidence: float = 0.95) -> float:
    """Student's t quantile of a two-sided `confidence` interval with `dof` degrees of freedom."""
    from scipy import stats as distributions

    return float(distributions.t.ppf(0.5 + confidence / 2, dof))


def korn_graubard(sums: np.ndarray, sizes: np.ndarray, confidence: float = 0.95) -> tuple[float, float]:
    """Korn and Graubard's interval for a clustered mean in [0, 1]: Clopper-Pearson at the effective sample size
    n* = p(1 - p) / v, with v the cluster-robust variance of the mean over trials and n* at most n, scaled by
    (t_{n-1} / t_{k-1})^2 for the k - 1 degrees of freedom of v. `sums` and `sizes`: each base instance's sum
    of values and number of trials.

    Values strictly between 0 and 1 (SPL) vary less than a Bernoulli variable of their mean, so for them the
    cap at n makes the interval conservative. With every value 0 (or every value 1) v is 0 and the design
    effect unknown; each base instance then counts once (n* = k), as if its trials were one: exact for bases whose
    trials all share one outcome, conservative otherwise. No variance was estimated there, so the degrees-of-freedom
    factor does not apply (with it, 5 of 5 over 3 bases read [0.05, 1]; 3 of 3 give [0.29, 1]). Korn, E. L. and
    Graubard, B. I., "Confidence intervals for proportions with small expected number of positive counts estimated
    from survey data", Survey Methodology 24(2), 1998.
    """
    n, k = float(sizes.sum()), len(sums)
    mean = float(sums.sum() / n)
    if k < 2:
        return clopper_pearson(mean, 1.0, confidence)
    if mean in (0.0, 1.0):
        return clopper_pearson(mean, float(k), confidence)
    degrees = (t_quantile(n - 1, confidence) / t_quantile(k - 1, confidence)) ** 2
    variance = k / (k - 1) * float(np.sum((sums - mean * sizes) ** 2)) / n**2
    effective = (min(n, mean * (1.0 - mean) / variance) if variance > 0.0 else n) * degrees
    return clopper_pearson(mean, effective, confidence)


def clopper_pearson(mean: float, n: float, confidence: float = 0.95) -> tuple[float, float]:
    """Clopper-Pearson's interval for `mean * n` successes of `n` trials (either may be fractional)."""
    from scipy import stats as distributions

    x, tail = mean * n, (1 - confidence) / 2
    low = 0.0 if x <= 0 else float(distributions.beta.ppf(tail, x, n - x + 1))
    high = 1.0 if x >= n else float(distributions.beta.ppf(1 - tail, x + 1, n - x))
    return (low, high)
