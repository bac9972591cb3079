"""The betting confidence sequence: time-uniform coverage, the paper's properties, and weights that target the
mean over trials."""

import math

import numpy as np
import pytest

from lerobot_contrast.contrast.confseq import (
    ConfidenceSequence,
    difference_bounds,
    difference_sequence,
    difference_unit,
)
from lerobot_contrast.contrast.stopping import excludes_zero


def run_streams(rng, values_of, streams, steps, alpha=0.05, **kwargs):
    cs = ConfidenceSequence(alpha, streams, **kwargs)
    lows, highs = [], []
    for _ in range(steps):
        cs.update(*values_of(rng, streams))
        lows.append(cs.low.copy())
        highs.append(cs.high.copy())
    return cs, np.array(lows), np.array(highs)


@pytest.mark.slow
@pytest.mark.parametrize("rate", [0.5, 0.03])
def test_it_covers_the_mean_at_every_time_in_at_least_95_percent_of_streams(rate):
    rng = np.random.default_rng(3)
    _, lows, highs = run_streams(rng, lambda r, b: ((r.random(b) < rate).astype(float),), 1000, 150)
    missed = ((lows > rate) | (highs < rate)).any(axis=0)
    assert missed.mean() <= 0.05, missed.mean()


def test_the_interval_only_narrows_and_holds_its_sample_mean():
    rng = np.random.default_rng(0)
    cs, lows, highs = run_streams(rng, lambda r, b: (r.beta(2, 5, size=b),), 20, 200)
    assert (np.diff(lows, axis=0) >= 0).all() and (np.diff(highs, axis=0) <= 0).all()
    assert ((cs.low <= cs.mean) & (cs.mean <= cs.high)).all()


def test_one_value_decides_nothing():
    """After X_1 = 1 the upward bet at m is at most 3/(4m), so the hedged wealth 1/2 (1 + 3 (1 - m) / (4m)) reaches
    1/alpha = 20 only below m = 3/159, where the plug-in bet sqrt(2 log 40 / (1/4 log 2)) = 6.5 caps it at 3.8."""
    cs = ConfidenceSequence(0.05)
    cs.update(1.0)
    assert (cs.low[0], cs.high[0]) == (0.0, 1.0)
    assert math.sqrt(2 * math.log(40) / (0.25 * math.log(2))) == pytest.approx(6.52, abs=0.01)


def test_it_adapts_to_low_variance_where_hoeffding_cannot():
    """Waudby-Smith and Ramdas' point: with rare successes the betting sequence is narrower than even the fixed-n
    Hoeffding interval, 2 sqrt(log(2 / alpha) / (2 n))."""
    rng = np.random.default_rng(1)
    n = 500
    cs, _, _ = run_streams(rng, lambda r, b: ((r.random(b) < 0.03).astype(float),), 50, n)
    hoeffding = 2 * math.sqrt(math.log(2 / 0.05) / (2 * n))
    assert np.median(cs.high - cs.low) < hoeffding / 2


def test_a_fixed_horizon_is_narrower_there_and_still_covers():
    rng = np.random.default_rng(2)
    draw = lambda r, b: ((r.random(b) < 0.3).astype(float),)  # noqa: E731
    anytime, _, _ = run_streams(rng, draw, 1000, 60)
    fixed, _, _ = run_streams(rng, draw, 1000, 60, horizon=60)
    assert np.mean(fixed.high - fixed.low) < np.mean(anytime.high - anytime.low)
    assert np.mean((fixed.low <= 0.3) & (fixed.high >= 0.3)) >= 0.95


def test_weights_make_it_cover_the_mean_over_trials_not_over_bases():
    """Bases of 10 trials all succeed, bases of 1 trial all fail, half each: the mean over bases is 0.5, the mean
    over trials 10/11."""
    rng = np.random.default_rng(4)

    def bases(r, b):
        big = r.random(b) < 0.5
        return np.where(big, 1.0, 0.0), np.where(big, 1.0, 0.1)

    cs, lows, highs = run_streams(rng, bases, 500, 300)
    truth = 10 / 11
    assert np.mean(((lows > truth) | (highs < truth)).any(axis=0)) <= 0.05
    assert (cs.low > 0.5).all()
    assert cs.mean == pytest.approx(np.full(500, truth), abs=0.05)


def test_missing_values_leave_a_stream_as_it_was():
    cs = ConfidenceSequence(0.05, 2)
    for _ in range(30):
        cs.update(np.array([0.2, np.nan]))
    assert cs.n.tolist() == [30, 0] and (cs.low[1], cs.high[1]) == (0.0, 1.0) and cs.high[0] < 1.0


def test_paired_differences_map_to_the_unit_interval_and_back():
    assert difference_unit(1.0, 0.0) == 1.0 and difference_unit(0.3, 0.3) == 0.5
    cs = ConfidenceSequence(0.05)
    low, high = difference_bounds(cs)
    assert (low[0], high[0]) == (-1.0, 1.0)


@pytest.mark.parametrize("alpha", [0.0, 1.0, -0.1])
def test_alpha_outside_the_unit_interval_is_refused(alpha):
    with pytest.raises(ValueError, match="alpha"):
        ConfidenceSequence(alpha)


def test_values_outside_the_unit_interval_are_refused():
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        ConfidenceSequence(0.05).update(1.5)


@pytest.mark.slow
def test_bets_tuned_to_a_target_width_still_cover_at_every_time_and_reach_it_sooner():
    rng = np.random.default_rng(5)
    draw = lambda r, b: ((r.random(b) < 0.4).astype(float),)  # noqa: E731
    _, lows, highs = run_streams(rng, draw, 500, 400, target_width=0.2)
    _, plain_lows, plain_highs = run_streams(rng, draw, 500, 400)
    assert np.mean(((lows > 0.4) | (highs < 0.4)).any(axis=0)) <= 0.05

    def first(lo, hi):  # the first update with the interval 0.2 wide (the number of updates where never)
        reached = hi - lo <= 0.2
        return np.where(reached.any(axis=0), np.argmax(reached, axis=0), len(reached))

    assert np.median(first(lows, highs)) < np.median(first(plain_lows, plain_highs))


def decided_at(sequence, differences):
    """Per stream: the first update after which the difference sequence leaves out 0 (-1: never)."""
    stop = np.full(differences.shape[1], -1)
    for t, d in enumerate(differences):
        sequence.update(difference_unit(d, 0.0))
        stop = np.where((stop < 0) & excludes_zero(*difference_bounds(sequence)), t, stop)
    return stop


def test_the_comparison_decides_a_large_difference_sooner_and_two_equal_policies_rarely():
    rng = np.random.default_rng(4)
    streams, steps = 400, 120
    clear = np.clip(rng.normal(0.4, 0.3, size=(steps, streams)), -1, 1)  # a base's mean paired difference
    comparison = decided_at(difference_sequence(0.05, streams), clear)
    interval = decided_at(ConfidenceSequence(0.05, streams), clear)
    assert (comparison >= 0).all() and comparison.mean() < interval.mean()
    equal = np.clip(rng.normal(0.0, 0.3, size=(steps, streams)), -1, 1)
    assert (decided_at(difference_sequence(0.05, streams), equal) >= 0).mean() <= 0.05
