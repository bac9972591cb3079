"""Sequential stopping rules, checked after every trial: stop once the anytime-valid interval of the headline metric
is narrower than `width`, or once the paired difference from a finished run of the same plan is decided.

Base instances are the i.i.d. units: a base's trials update the confidence sequences when its last planned trial is
recorded. For the headline metric each base is weighted by its share of the most trials any base has planned, so the
interval covers the mean over trials (see confseq); the comparison weighs every base alike (the mean over bases of
each base's mean paired difference, 0 for two equal policies), which decides sooner. The state is a
function of the records in trial order, so a resumed run rebuilds it from its journal exactly.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from lerobot_contrast.contrast.confseq import (
    ConfidenceSequence,
    difference_bounds,
    difference_sequence,
    difference_unit,
)
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.intervals import korn_graubard
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.trial import TrialRecord

HEADLINE_METRICS = ("spl", "progress")  # the report's rule: SPL where recorded, else subgoal progress


class StopError(UserError):
    pass


@dataclass(frozen=True)
class StopRule:
    """`width`: stop when the headline metric's anytime-valid interval is at most this wide. `reference`: the
    headline value of each done trial of the run compared against (by `trial_key`), in `metric`. `alpha`:
    1 - confidence."""

    width: float | None = None
    alpha: float = 0.05
    reference: Mapping[tuple[str, str | None, int], float] | None = None
    reference_name: str = ""
    metric: str | None = None  # the headline metric; None: the first done trial decides (see `headline_metric`)
    # Count only the original instances: with --order=adaptive, which perturbations run on a base depends on earlier
    # outcomes, so only the originals stay an i.i.d. sample of one mean.
    originals_only: bool = False

    def __post_init__(self) -> None:
        if self.width is not None and not 0.0 < self.width < 1.0:
            raise StopError(f"--stop.width must be between 0 and 1 (exclusive), got {self.width:g}")
        if not 0.0 < self.alpha < 1.0:
            raise StopError(f"--stop.alpha must be between 0 and 1 (exclusive), got {self.alpha:g}")

    @property
    def active(self) -> bool:
        return self.width is not None or self.reference is not None


def excludes_zero(low: Any, high: Any) -> Any:
    """A paired comparison is decided once its interval for the difference leaves out 0 (arrays work too)."""
    return (np.asarray(low) > 0.0) | (np.asarray(high) < 0.0)


def headline_metric(records: Iterable[TrialRecord]) -> str:
    """SPL where any done trial recorded it, else subgoal progress (success itself for tasks without subgoals)."""
    return "spl" if any(r.status == "done" and r.spl is not None for r in records) else "progress"


def headline_value(record: TrialRecord, metric: str) -> float | None:
    if record.status != "done":
        return None
    value = getattr(record, metric)
    return None if value is None else float(value)


class Monitor:
    """The sequential state of one run: fed each record in trial order by `observe`, it says when to stop."""

    def __init__(self, plan: list[PlannedTrial], rule: StopRule) -> None:
        self.rule, self.metric = rule, rule.metric
        counted = [t for t in plan if self._counts(t)]
        self.remaining = dict(zip(*np.unique([t.base.id for t in counted], return_counts=True), strict=True))
        self.most_trials = float(max(self.remaining.values(), default=1))
        self.open: dict[str, list[tuple[float, float | None]]] = {}
        self.interval = ConfidenceSequence(rule.alpha, target_width=rule.width)  # bets tuned to reach the width
        self.difference = difference_sequence(rule.alpha) if rule.reference is not None else None
        self.sums: list[float] = []  # per complete base: sum of its values and number, for the fixed-n interval
        self.sizes: list[float] = []
        self.reason: str | None = None

    def observe(self, record: TrialRecord) -> str | None:
        """Take one record; return why the run stops now, or None to go on."""
        if record.status == "done":
            self._check_metric(record)
        value = None if self.metric is None else headline_value(record, self.metric)
        if not self._counts(record):
            value = None
        if value is not None:
            other = None if self.rule.reference is None else self.rule.reference.get(trial_key(record))
            self.open.setdefault(record.base_id, []).append((value, other))
        if self._counts(record) and record.base_id in self.remaining:
            self.remaining[record.base_id] -= 1
            if self.remaining[record.base_id] == 0:  # the base's last counted trial: it joins as one unit
                self._close(self.open.pop(record.base_id, []))
        if self.reason is None:
            self.reason = self._verdict()
        return self.reason

    def _counts(self, trial: PlannedTrial | TrialRecord) -> bool:
        return not (self.rule.originals_only and trial.perturbation is not None)

    def _check_metric(self, record: TrialRecord) -> None:
        own = headline_metric([record])
        if self.metric is None:
            self.metric = own
        elif own != self.metric:
            source = (
                f"{self.rule.reference_name}'s" if self.rule.reference is not None else "this run's earlier trials'"
            )
            raise StopError(
                f"--stop: trial {record.index} has headline metric {own}, but {source} is {self.metric}; "
                "compare runs of the same task and release"
            )

    def _close(self, values: list[tuple[float, float | None]]) -> None:
        """A base is complete: its mean (and mean paired difference) joins the sequences as one unit."""
        if values:
            own = np.array([v for v, _ in values])
            self.interval.update(own.mean(), len(own) / self.most_trials)
            self.sums.append(float(own.sum()))
            self.sizes.append(float(len(own)))
        paired = [(v, o) for v, o in values if o is not None]
        if self.difference is not None and paired:
            a, b = np.array(paired).T
            self.difference.update(difference_unit(a, b).mean())

    def _verdict(self) -> str | None:
        if self.difference is not None and excludes_zero(*self.bounds_difference()):
            return "decided"
        if self.rule.width is not None and self.sizes and self.high - self.low <= self.rule.width:
            return "width"
        return None

    @property
    def bases(self) -> int:
        return len(self.sizes)

    def fixed_n(self) -> tuple[float, float]:
        """The report's fixed-n interval over the complete bases: right only if this size was fixed in advance."""
        if not self.sizes:
            return (0.0, 1.0)
        return korn_graubard(np.array(self.sums), np.array(self.sizes), 1 - self.rule.alpha)

    @property
    def low(self) -> float:
        return float(self.interval.low[0])

    @property
    def high(self) -> float:
        return float(self.interval.high[0])

    def bounds_difference(self) -> tuple[float, float]:
        low, high = difference_bounds(self.difference)
        return float(low[0]), float(high[0])

    def state(self) -> dict[str, Any]:
        """What each trial's journal line records of the sequential test after it."""
        out: dict[str, Any] = {"bases": self.bases, "anytime_interval": [self.low, self.high], "stop": self.reason}
        if self.difference is not None:
            out["difference_interval"] = list(self.bounds_difference())
        return out

    def report(self, planned_end: bool) -> dict[str, Any]:
        """What the summary says: the rule, why the run stopped, and the anytime-valid intervals at that point."""
        out: dict[str, Any] = {
            "metric": self.metric,
            "alpha": self.rule.alpha,
            "width": self.rule.width,
            "complete_bases": self.bases,
            "mean": float(sum(self.sums) / sum(self.sizes)) if self.sizes else None,
            "anytime_interval": [self.low, self.high],
            "fixed_n_interval": list(self.fixed_n()),
            "reason": self.reason or ("plan_end" if planned_end else "not_stopped"),
            "why": reason_text(self.reason or ("plan_end" if planned_end else "not_stopped"), self.rule),
        }
        if self.difference is not None:
            low, high = self.bounds_difference()
            verdict = "undecided" if low <= 0.0 <= high else ("better" if low > 0.0 else "worse")
            out |= {"compare": self.rule.reference_name, "difference_interval": [low, high], "verdict": verdict}
        return out

    def line(self) -> str:
        """The console's view: the fixed-n interval beside the anytime-valid one (and the difference), labelled
        so that only the second reads as safe to stop on."""
        level = f"{100 * (1 - self.rule.alpha):g}%"
        low, high = self.fixed_n()
        text = f"{self.metric}: fixed-n {level} [{low:.3f}, {high:.3f}] | "
        text += f"anytime-valid {level} CS [{self.low:.3f}, {self.high:.3f}]"
        if self.difference is not None:
            low, high = self.bounds_difference()
            text += f", diff vs {self.rule.reference_name} [{low:+.3f}, {high:+.3f}]"
        return text + f" ({self.bases} bases)"


def summary_line(report: Mapping[str, Any]) -> str:
    """The console's closing line on the sequential test, from `Monitor.report`."""
    low, high = report["anytime_interval"]
    level = f"{100 * (1 - report['alpha']):g}%"
    text = f"sequential: {report['why']}; {report['metric']} anytime-valid {level} CS [{low:.3f}, {high:.3f}]"
    text += f" over {report['complete_bases']} bases"
    if "verdict" in report:
        d_low, d_high = report["difference_interval"]
        text += f"; vs {report['compare']}: {report['verdict']} (difference [{d_low:+.3f}, {d_high:+.3f}])"
    return text


def reason_text(reason: str, rule: StopRule) -> str:
    """One sentence for the summary and console."""
    return {
        "decided": f"the paired difference from {rule.reference_name} was decided at alpha={rule.alpha:g}",
        "width": f"the anytime-valid interval was at most {rule.width} wide",
        "plan_end": "the plan (or its budget) ended before any stopping rule fired",
        "not_stopped": "the run was interrupted or ran out of budget before any stopping rule fired",
    }[reason]


def trial_key(record: TrialRecord) -> tuple[str, str | None, int]:
    """What pairs a trial with the compared run's: its base, perturbation and repeat (indices differ under
    --order=adaptive)."""
    return (record.base_id, record.perturbation, record.repeat)


def reference_values(records: Iterable[TrialRecord], metric: str) -> dict[tuple[str, str | None, int], float]:
    """The compared run's headline value per trial (done trials only), by `trial_key`."""
    out = {}
    for record in records:
        value = headline_value(record, metric)
        if value is not None and math.isfinite(value):
            out[trial_key(record)] = value
    return out
