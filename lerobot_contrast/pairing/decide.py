"""The paired sequential test of every pair of policies, per base, with the family-wise error kept at alpha.

Each pair's mean per-base paired difference (as `--stop.compare` computes it: the base's mean of the headline metric's
per-trial differences) gets an anytime-valid confidence sequence at alpha / m for m pairs (Bonferroni). Each sequence
covers its true difference at every time with probability at least 1 - alpha / m, so all m do at once with
probability at least 1 - alpha, at any stopping time: stopping when the pairs are decided keeps that error.
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from lerobot_contrast.contrast.confseq import difference_bounds, difference_sequence, difference_unit
from lerobot_contrast.contrast.stopping import excludes_zero, headline_metric, headline_value
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.trial import TrialRecord


class PairTest:
    """The sequential comparison of policy `a` with policy `b` (difference a - b)."""

    def __init__(self, a: str, b: str, alpha: float) -> None:
        self.a, self.b, self.alpha = a, b, alpha
        self.sequence = difference_sequence(alpha)
        self.open: dict[str, list[tuple[float, float]]] = {}
        self.bases = 0
        self.decided_at: int | None = None  # the number of complete bases when it was decided

    def add(self, base: str, a: float | None, b: float | None) -> None:
        if a is not None and b is not None:
            self.open.setdefault(base, []).append((a, b))

    def close(self, base: str) -> None:
        values = self.open.pop(base, [])
        self.bases += 1
        if values:
            own, other = np.array(values).T
            self.sequence.update(difference_unit(own, other).mean())
        if self.decided_at is None and self.decided:
            self.decided_at = self.bases

    @property
    def interval(self) -> tuple[float, float]:
        low, high = difference_bounds(self.sequence)
        return float(low[0]), float(high[0])

    @property
    def decided(self) -> bool:
        return bool(excludes_zero(*self.interval))

    def report(self) -> dict[str, Any]:
        low, high = self.interval
        verdict = "undecided" if not self.decided else ("first better" if low > 0 else "second better")
        return {
            "first": self.a, "second": self.b, "alpha": self.alpha, "difference_interval": [low, high],
            "verdict": verdict, "decided_at_bases": self.decided_at, "bases": self.bases,
        }  # fmt: skip


class PairMonitor:
    """Every pair's test, fed each trial's records of all policies once the trial is done by all."""

    def __init__(self, plan: Sequence[PlannedTrial], labels: Sequence[str], alpha: float) -> None:
        pairs = list(itertools.combinations(labels, 2))
        self.family_alpha = alpha
        self.tests = [PairTest(a, b, alpha / len(pairs)) for a, b in pairs]
        self.remaining = Counter(t.base.id for t in plan)
        self.metric: str | None = None
        self.bases = 0

    def observe(self, records: Mapping[str, TrialRecord]) -> None:
        first = next(iter(records.values()))
        if self.metric is None and any(r.status == "done" for r in records.values()):
            self.metric = headline_metric(r for r in records.values() if r.status == "done")
        values = {k: None if self.metric is None else headline_value(r, self.metric) for k, r in records.items()}
        for test in self.tests:
            test.add(first.base_id, values[test.a], values[test.b])
        self.remaining[first.base_id] -= 1
        if self.remaining[first.base_id] == 0:
            self.bases += 1
            for test in self.tests:
                test.close(first.base_id)

    @property
    def all_decided(self) -> bool:
        return all(test.decided for test in self.tests)

    def report(self) -> dict[str, Any]:
        return {
            "metric": self.metric,
            "alpha": self.family_alpha,
            "correction": f"Bonferroni over {len(self.tests)} pair(s): each pair at alpha/{len(self.tests)}",
            "complete_bases": self.bases,
            "pairs": [test.report() for test in self.tests],
        }

    def line(self) -> str:
        parts = [f"{t.a} - {t.b} [{t.interval[0]:+.3f}, {t.interval[1]:+.3f}]" for t in self.tests]
        return f"paired {self.metric} after {self.bases} bases: " + "; ".join(parts)
