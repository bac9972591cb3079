"""Stopping rules: the width and comparison verdicts, per-base updates, and a rebuilt state equal to the live one."""

import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.stopping import Monitor, StopError, StopRule, reference_values
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.trial import TrialRecord


def plan_of(bases, per_base):
    plan = []
    for j in range(bases):
        base = Instance(id=f"b{j}", family="f", instruction="go", scene=Scene())
        start = len(plan)
        plan.extend(PlannedTrial(start + k, base, None if k == 0 else f"P{k}", "reset") for k in range(per_base))
    return plan


def record(trial, success, spl=None, status="done"):
    return TrialRecord(
        trial.index, trial.base.id, trial.perturbation, None, "f", "reset", 0, status, trial.base, 0.0, 0.0,
        success, spl, float(success),
    )  # fmt: skip


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"width": 0.0}, "--stop.width"),
        ({"width": 1.0}, "--stop.width"),
        ({"width": -0.1}, "--stop.width"),
        ({"alpha": 0.0}, "--stop.alpha"),
        ({"alpha": 1.5}, "--stop.alpha"),
    ],
)
def test_a_width_or_alpha_outside_the_unit_interval_is_refused(kwargs, message):
    with pytest.raises(StopError, match=message):
        StopRule(**kwargs)


def test_bases_join_the_sequence_when_their_last_planned_trial_is_recorded():
    plan = plan_of(3, 3)
    monitor = Monitor(plan, StopRule(width=0.5))
    for trial in plan[:2]:
        monitor.observe(record(trial, True))
    assert monitor.bases == 0 and (monitor.low, monitor.high) == (0.0, 1.0)
    monitor.observe(record(plan[2], True))
    assert monitor.bases == 1 and monitor.metric == "progress"


def test_the_width_rule_fires_once_the_anytime_interval_is_narrow_enough_and_a_replay_agrees():
    plan = plan_of(200, 2)
    monitor = Monitor(plan, StopRule(width=0.3))
    stopped_at = None
    for trial in plan:
        if monitor.observe(record(trial, trial.index % 4 != 0)) is not None:
            stopped_at = trial.index
            break
    assert stopped_at is not None and monitor.high - monitor.low <= 0.3 < 1.0
    assert stopped_at % 2 == 1  # only a base's last trial moves the interval
    replay = Monitor(plan, StopRule(width=0.3))
    for trial in plan[: stopped_at + 1]:
        replay.observe(record(trial, trial.index % 4 != 0))
    assert replay.report(planned_end=False) == monitor.report(planned_end=False)
    assert monitor.report(planned_end=False)["reason"] == "width"
    assert "at most 0.3 wide" in monitor.report(planned_end=False)["why"]


def test_a_clearly_better_policy_is_decided_and_equal_ones_are_not():
    plan = plan_of(60, 3)
    worse = reference_values([record(t, False) for t in plan], "progress")
    rule = StopRule(alpha=0.05, reference=worse, reference_name="runs/worse")
    monitor = Monitor(plan, rule)
    reasons = [monitor.observe(record(t, True)) for t in plan]
    assert "decided" in reasons and reasons.index("decided") < len(plan) - 1
    assert monitor.report(planned_end=False)["verdict"] == "better"
    same = reference_values([record(t, t.index % 2 == 0) for t in plan], "progress")
    even = Monitor(plan, StopRule(reference=same, reference_name="runs/same"))
    assert all(even.observe(record(t, t.index % 2 == 0)) is None for t in plan)
    report = even.report(planned_end=True)
    assert (report["reason"], report["verdict"]) == ("plan_end", "undecided")
    assert "diff vs runs/same" in even.line() and "| anytime-valid 95% CS [" in even.line()
    assert even.line().startswith("progress: fixed-n 95% [")


def test_trials_without_a_value_do_not_count_and_missing_spl_is_refused():
    plan = plan_of(2, 2)
    monitor = Monitor(plan, StopRule(width=0.5))
    monitor.observe(record(plan[0], True, spl=0.9))
    monitor.observe(record(plan[1], False, status="not_applicable"))
    assert monitor.metric == "spl" and monitor.bases == 1
    with pytest.raises(StopError, match="headline metric progress, but this run's earlier trials' is spl"):
        monitor.observe(record(plan[2], True, spl=None))


def test_with_adaptive_order_only_the_originals_count():
    plan = plan_of(3, 2)
    monitor = Monitor(plan, StopRule(width=0.5, originals_only=True))
    for trial in plan:
        monitor.observe(record(trial, trial.perturbation is None))
    assert monitor.bases == 3 and sum(monitor.sums) == 3 and sum(monitor.sizes) == 3
