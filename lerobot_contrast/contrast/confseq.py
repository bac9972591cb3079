"""Anytime-valid confidence sequences for a mean in [0, 1] by betting: Waudby-Smith and Ramdas, "Estimating means
of bounded random variables by betting", JRSS-B 86(1), 2024 (the hedged capital process of their Theorem 3 with
predictable plug-in bets, their eq. 26-27 and section 4.2), and at a horizon fixed in advance the paper's betting
confidence interval (section 5.1: the same bets tuned to n).

For each candidate mean m on a grid, two gamblers bet on X - m and on m - X. Under the true mean both wealths are
nonnegative martingales, so by Ville's inequality the true mean is excluded at some time with probability at most
alpha. The interval is the set of m where neither has reached 1/alpha, intersected over time. Arrays carry a
leading batch axis so that thousands of simulated studies update at once.

A unit may carry a weight w in (0, 1]: with x the mean of a base's N trials and w = N / N_max, each factor
1 + bet * w * (x - m) has conditional mean 1 when m = E[sum of trial values] / E[N], so the sequence covers the
mean over trials (the ratio estimate the report shows), not the mean over bases. Bets are divided by the mean
weight of the earlier units (a predictable scale, so the wealth stays a martingale) before truncation.
"""

from __future__ import annotations

import math

import numpy as np

GRID_POINTS = 1001
# c in the paper: bets at most c/m (or c/(1-m)), keeping every factor of the wealth above 1-c. The paper suggests
# 1/2 or 3/4 for an interval.
TRUNCATION = 0.75
# A paired comparison tests one point, 0 difference, and policies worth telling apart differ by a lot per base: the
# bets that decide soonest there are at the bound (scripts/study/savings_sequential.py prints the best constant bet), so
# its sequence lets them go nearer it. On 50-base runs, 0.9 against 0.75 decides in 12.8 rather than 14.8 bases
# (learned default vs oracle) and 31.8 rather than 35.0 (vs its copy with 2 cm of action noise).
DIFFERENCE_TRUNCATION = 0.9
HEDGE = 0.5  # theta: the weight of the upward bettor


class ConfidenceSequence:
    """A running betting confidence sequence at level 1 - `alpha` for `batch` independent streams of values in [0, 1].

    `update` adds one value per stream (NaN: no value for that stream this round); `low` and `high` hold the
    interval, valid simultaneously at every number of updates. Any predictable bets keep that validity (Ville's
    inequality); their size decides where the interval is narrow. By default the bets spread over all times
    (t log t); with `horizon` (a number of units fixed in advance: the paper's confidence interval) they are tuned to
    that many units; with `target_width` to the number of units at which an interval of that width is expected,
    8 log(2/alpha) sigma^2 / width^2, estimated from the values so far.
    """

    def __init__(
        self,
        alpha: float,
        batch: int = 1,
        grid_points: int = GRID_POINTS,
        horizon: int | None = None,
        target_width: float | None = None,
        truncation: float = TRUNCATION,
    ) -> None:
        if not 0.0 < alpha < 1.0:
            raise ValueError(f"alpha must be in (0, 1), got {alpha}")
        self.alpha = alpha
        self.horizon, self.target_width, self.truncation = horizon, target_width, truncation
        self.grid = np.linspace(0.0, 1.0, grid_points)
        self.step = 1.0 / (grid_points - 1)
        self.n = np.zeros(batch)
        self.total = np.zeros(batch)  # sum of values
        self.weighted = np.zeros(batch)  # sum of weight * value, and of weights: the point estimate
        self.weights = np.zeros(batch)
        self.squares = np.full(batch, 0.25)  # 1/4 + sum of (x_i - mu_hat_i)^2: the plug-in variance's numerator
        self.log_up = np.zeros((batch, grid_points))
        self.log_down = np.zeros((batch, grid_points))
        self.low = np.zeros(batch)
        self.high = np.ones(batch)

    def update(self, x: np.ndarray | float, weight: np.ndarray | float = 1.0) -> None:
        x = np.broadcast_to(np.asarray(x, dtype=np.float64), self.n.shape)
        has = ~np.isnan(x)
        if np.any((x[has] < 0.0) | (x[has] > 1.0)):
            raise ValueError("values must lie in [0, 1]")
        t = self.n + 1.0
        variance = self.squares / t  # sigma_hat^2_{t-1}: the (t-1) values seen so far plus the prior 1/4
        spread = self._spread(t, variance)
        bet = np.sqrt(2.0 * math.log(2.0 / self.alpha) / (variance * spread))
        bet /= (1.0 + self.weights) / t  # the bet on w (x - m): scaled by the mean weight so far (prior 1)
        w = np.broadcast_to(np.asarray(weight, dtype=np.float64), self.n.shape)[:, None]
        m = self.grid[None, :]
        with np.errstate(divide="ignore"):  # truncate, then weight: the factor stays linear in w
            up = np.minimum(bet[:, None], self.truncation / m) * w
            down = np.minimum(bet[:, None], self.truncation / (1.0 - m)) * w
        value = np.where(has, x, 0.0)[:, None]
        keep = has[:, None]
        self.log_up += np.where(keep, np.log1p(up * (value - m)), 0.0)
        self.log_down += np.where(keep, np.log1p(-down * (value - m)), 0.0)
        self.weighted += np.where(has, w[:, 0] * x, 0.0)
        self.weights += np.where(has, w[:, 0], 0.0)
        self.total += np.where(has, x, 0.0)
        self.n += has
        estimate = (0.5 + self.total) / (self.n + 1.0)  # mu_hat_t, including this value
        self.squares += np.where(has, (np.where(has, x, 0.0) - estimate) ** 2, 0.0)
        self._narrow(has)

    def _spread(self, t: np.ndarray, variance: np.ndarray) -> np.ndarray:
        """The number of units the bets are tuned for (the bet falls with its square root)."""
        if self.horizon is not None:
            return np.full_like(t, float(self.horizon))
        if self.target_width is not None:
            return np.maximum(t, 8.0 * math.log(2.0 / self.alpha) * variance / self.target_width**2)
        return t * np.log1p(t)

    def _narrow(self, updated: np.ndarray) -> None:
        """Intersect the interval with the grid points still plausible (widened by one grid step, since the
        excluded region between grid points is not checked)."""
        threshold = math.log(1.0 / self.alpha)
        hedged = np.maximum(math.log(HEDGE) + self.log_up, math.log(1.0 - HEDGE) + self.log_down)
        plausible = hedged < threshold
        anywhere = plausible.any(axis=1)
        first = np.where(anywhere, np.argmax(plausible, axis=1), np.argmin(hedged, axis=1))
        last = np.where(anywhere, len(self.grid) - 1 - np.argmax(plausible[:, ::-1], axis=1), first)
        low = np.maximum(self.low, self.grid[first] - self.step)
        high = np.minimum(self.high, self.grid[last] + self.step)
        crossed = low > high  # an empty intersection (probability at most alpha): keep the point where they met
        middle = (low + high) / 2
        self.low = np.where(updated, np.where(crossed, middle, np.clip(low, 0.0, 1.0)), self.low)
        self.high = np.where(updated, np.where(crossed, middle, np.clip(high, 0.0, 1.0)), self.high)

    @property
    def mean(self) -> np.ndarray:
        """The weighted mean of the values so far (the mean over trials, for weights proportional to trials)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.weights > 0, self.weighted / self.weights, np.nan)


def difference_sequence(alpha: float, batch: int = 1) -> ConfidenceSequence:
    """The sequence `--stop.compare` decides on: of `difference_unit` values, with bets allowed nearer the bound."""
    return ConfidenceSequence(alpha, batch, truncation=DIFFERENCE_TRUNCATION)


def difference_unit(a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray:
    """A paired difference a - b of values in [0, 1], mapped to [0, 1] for `ConfidenceSequence` (0 -> 0.5)."""
    return (np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64) + 1.0) / 2.0


def difference_bounds(sequence: ConfidenceSequence) -> tuple[np.ndarray, np.ndarray]:
    """The interval of the mean difference a - b from a sequence fed with `difference_unit` values."""
    return 2.0 * sequence.low - 1.0, 2.0 * sequence.high - 1.0
