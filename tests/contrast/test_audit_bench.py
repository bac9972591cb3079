"""The audit's coverage benchmark (scripts/bench/bench_audit.py): its bound on what any interval must cover, and the
audited intervals covering where the camera's own do not."""

import numpy as np
import pytest

from tests.study_scripts import load_script

bench = load_script("bench_audit")


def test_the_least_coverage_bound():
    # Every session unseen and the camera unbiased: the interval must cover 0.94 itself.
    assert bench.least_coverage_max(1.0, 0.0) == pytest.approx(0.94)
    # A camera seven standard errors off, unseen in a quarter of sessions: the right camera's coverage is near 1.
    assert bench.least_coverage_max(0.25, 7.0) > 0.999
    # Unseen in under 6 % of sessions: covering every other session is enough, whatever the interval.
    assert bench.least_coverage_max(0.05, 7.0) == 0.0


def test_audited_intervals_cover_where_a_skewed_camera_misleads():
    rates = bench.base_rates(np.random.default_rng(0), 200_000)
    truth = (rates[:, 1 + bench.PERTURBATIONS.index("S")] - rates[:, 0]).mean()
    rng = np.random.default_rng(1)
    runs = [bench.session(rng, 60, 0.05, "on_S", 0.2)[0] for _ in range(200)]
    covered = {
        k: np.mean([low <= truth <= high for low, high in (r[k] for r in runs)]) for k in ("change", "change_camera")
    }
    assert covered["change"] >= 0.93 and covered["change_camera"] < 0.5
