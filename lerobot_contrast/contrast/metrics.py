"""Episode metrics: success, success weighted by path length (SPL), and subgoal progress; `score` and `scored` are
the one place an outcome becomes metrics and a scored record."""

from __future__ import annotations

from lerobot_contrast.contrast.trial import Outcome, TrialContext, TrialRecord


def spl(success: bool, reference_length: float, path_length: float) -> float:
    """Success weighted by path length: S * l / max(l, p) for reference l and actual p (Anderson et al. 2018)."""
    if not success:
        return 0.0
    if reference_length <= 0.0:
        return 1.0
    return reference_length / max(reference_length, path_length)


def subgoal_progress(subgoals_reached: int, n_subgoals: int) -> float:
    """Fraction of subgoals reached in order (VLN: 0.5 for the first of two, 1.0 for both)."""
    if n_subgoals <= 0:
        raise ValueError("n_subgoals must be positive")
    return min(max(subgoals_reached, 0), n_subgoals) / n_subgoals


METRICS = ("success", "spl", "progress")
# How reports, figures and the viewer name each metric.
METRIC_NAMES = {"spl": "SPL", "success": "success rate", "progress": "subgoal progress"}


def score(outcome: Outcome) -> dict[str, bool | float | None]:
    """The one place an outcome becomes metrics: success, SPL (None without a reference path) and progress
    (success itself where the task has no subgoals)."""
    reference = outcome.reference_length
    return {
        "success": outcome.success,
        "spl": None if reference is None else spl(outcome.success, reference, outcome.path_length),
        "progress": outcome.progress if outcome.progress is not None else float(outcome.success),
    }


def scored(
    context: TrialContext, outcome: Outcome, cost: float, cumulative_cost: float, started_at: str | None = None
) -> TrialRecord:
    """The journal's record of a trial that ran: what was staged, what it cost, and its scores."""
    instance = context.instance
    return TrialRecord(
        index=context.index,
        base_id=context.base.id,
        perturbation=instance.perturbation,
        axis=context.axis,
        family=instance.family,
        staging=context.staging,
        repeat=context.repeat,
        status=outcome.status,
        instance=instance,
        cost=cost,
        cumulative_cost=cumulative_cost,
        **score(outcome),
        path_length=outcome.path_length,
        reference_length=outcome.reference_length,
        steps=outcome.steps,
        duration_s=outcome.duration_s,
        started_at=started_at,
        scene_after=outcome.scene_after,
        extra=dict(outcome.extra),
    )
