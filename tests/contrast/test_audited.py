"""Audited labels: the audit's draw is reproducible and blind to the labels, and the prediction-powered estimate
matches a worked example computed by hand."""

import math

import numpy as np
import pytest

from lerobot_contrast.contrast.audited import audited, paired_change, rate
from lerobot_contrast.contrast.intervals import t_quantile


def test_the_audit_draws_its_share_reproducibly_and_from_the_seed_and_trial_alone():
    draws = [audited(7, index, 0.1) for index in range(2000)]
    assert draws == [audited(7, index, 0.1) for index in range(2000)]  # the same seed, the same draw
    assert 0.08 < np.mean(draws) < 0.12
    assert draws != [audited(8, index, 0.1) for index in range(2000)]
    assert not any(audited(7, index, 0.0) for index in range(100)) and all(audited(7, i, 1.0) for i in range(100))


def test_the_estimate_matches_a_worked_example():
    # Six trials of three bases; trials 0, 3 and 4 audited (half), and the person agrees with the camera on each.
    labels, audit = [1, 1, 0, 1, 0, 1], [True, False, False, True, True, False]
    person, bases = [1, None, None, 1, 0, None], ["a", "a", "b", "b", "c", "c"]
    said = rate(labels, audit, person, bases)
    # u = a*y/p = [2,0,0,2,0,0], v = f*(1-a/p) = [-1,1,0,-1,0,1]; per base U = [2,2,0], V = [0,-1,1].
    # r = U - (2/3)*2 = [2/3, 2/3, -4/3], s = V: r.s = -2, s.s = 2, the clustered spread 3/2 / 36 = 1/24. Laplace's
    # four pseudo-trials over three audited: floor 4/7 / 3 / 4 = 1/21. lambda = (2/24) / (2/24 + 1/21) = 7/11.
    assert (said.mean, said.weight, said.n_audited, said.n_clusters) == (
        pytest.approx(2 / 3),
        pytest.approx(7 / 11),
        3,
        3,
    )
    # residual r + 7/11 s = [2/3, 1/33, -23/33], |.|^2 = 1014/1089; plus the floor times 1 + 49/121.
    half = t_quantile(2) * math.sqrt(1014 / 1089 / 24 + 170 / 121 / 21)
    assert (said.low, said.high) == (pytest.approx(max(0.0, 2 / 3 - half)), pytest.approx(min(1.0, 2 / 3 + half)))


def test_a_small_audit_whose_labels_are_all_alike_still_has_an_interval():
    # Three of 120 trials audited, every one a failure the camera saw as one: the audit alone looks certain (its
    # variance is 0), and without the floor lambda took it, giving the interval [0, 0] around a rate near 0.4.
    rng = np.random.default_rng(3)
    labels = (rng.random(120) < 0.4).astype(float)
    audit = np.zeros(120, bool)
    audit[np.flatnonzero(labels == 0)[:3]] = True
    said = rate(labels, audit, np.where(audit, labels, np.nan), np.repeat(np.arange(60), 2))
    assert said.high - said.low > 0.2 and said.low < labels.mean() < said.high


def test_with_a_camera_that_always_says_success_the_estimate_follows_the_audit():
    rng = np.random.default_rng(0)
    truth = (rng.random(600) < 0.4).astype(float)
    audit = rng.random(600) < 0.2
    said = rate(np.ones(600), audit, np.where(audit, truth, np.nan), np.repeat(np.arange(120), 5))
    # The camera's label tells nothing, so the estimate is the audit's mean whatever lambda (which here only evens
    # out how many trials each base had audited).
    assert said.mean == pytest.approx(truth[audit].mean()) and said.low < 0.4 < said.high


def test_a_paired_change_is_estimated_over_bases():
    rng = np.random.default_rng(1)
    original, perturbed = (rng.random(200) < 0.7).astype(float), (rng.random(200) < 0.4).astype(float)
    labels = np.stack([original, perturbed], 1).ravel()
    audit = rng.random(400) < 0.3
    said = paired_change(labels, audit, labels, np.repeat(np.arange(200), 2), np.tile([False, True], 200))
    assert said.weight == 1.0 and said.mean == pytest.approx((perturbed - original).mean())  # a camera never wrong
    assert said.low < -0.3 < said.high and said.n_clusters == 200


def test_no_audit_gives_no_interval():
    said = rate([1, 0, 1], [False, False, False], [None, None, None], ["a", "b", "c"])
    assert math.isnan(said.mean) and said.n_audited == 0
