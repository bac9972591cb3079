"""The evaluation loop: next trial -> stage its scene (pay the cost) -> run -> score -> record."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import numpy as np

from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.metrics import spl
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.staging import Staged, materialize, trial_rng
from lerobot_contrast.contrast.strategy import PlannedTrial, exceeds_budget
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import Outcome, TrialRecord
from lerobot_contrast.runners.episode import TrialContext

Execute = Callable[[TrialContext], Outcome]
# Trials whose staging was paid for: the scene they left behind is where the next one starts.
STAGED = ("done", "aborted")


class BudgetError(UserError):
    pass


@dataclass
class LoopState:
    """Where the evaluation stands: the scene the robot left behind and the effort spent so far."""

    scene: Scene
    cumulative_cost: float = 0.0
    previous: Staged | None = None
    next_index: int = 0

    @classmethod
    def resume(cls, records: list[TrialRecord], initial_scene: Scene) -> LoopState:
        state = cls(scene=initial_scene, next_index=len(records))
        for record in records:
            state.previous = Staged(record.instance, record.staging)
            if record.status in STAGED and record.scene_after is not None:
                state.scene = record.scene_after
                state.cumulative_cost = record.cumulative_cost
        return state


def check_budget(
    plan: list[PlannedTrial], task: Task, cost_model: CostModel, budget: float | None, seed: int, initial_scene: Scene
) -> None:
    """Refuse a budget that cannot pay for staging the first trial."""
    if budget is None or not plan:
        return
    if budget <= 0:
        raise BudgetError(f"--budget must be positive ({cost_model.unit}), got {budget}")
    first = materialize(plan[0], task, initial_scene, None, trial_rng(seed, 0))
    if first.instance is None:
        return
    cost = cost_model(initial_scene, first.instance.scene)
    if budget < cost:
        raise BudgetError(
            f"--budget {budget:g} {cost_model.unit} is below the cost of staging the first trial "
            f"({cost:.2f} {cost_model.unit}); raise --budget or drop it for no limit"
        )


def run_trials(
    plan: list[PlannedTrial],
    task: Task,
    cost_model: CostModel,
    budget: float | None,
    seed: int,
    state: LoopState,
    execute: Execute,
    settings: Mapping[str, Any] | None = None,
) -> Iterator[TrialRecord]:
    """Execute the plan from `state.next_index`, yielding one record per trial, until done or over budget."""
    for trial in plan[state.next_index :]:
        if exceeds_budget(state.cumulative_cost, budget):
            return
        staged = materialize(trial, task, state.scene, state.previous, trial_rng(seed, trial.index))
        state.previous = staged
        state.next_index = trial.index + 1
        if staged.instance is None:
            yield _skipped(trial, task, state.cumulative_cost)
            continue
        context = TrialContext(
            index=trial.index,
            instance=staged.instance,
            base=trial.base,
            current=state.scene,
            planned_cost=cost_model(state.scene, staged.instance.scene),
            staging=staged.staging,
            rng=np.random.default_rng([seed, trial.index, 1]),
            planned_trials=len(plan),
            axis=_axis(task, trial.perturbation),
            settings=dict(settings or {}),
        )
        started_at = datetime.now(UTC).isoformat(timespec="seconds")
        outcome = execute(context)
        cost = context.planned_cost if outcome.cost is None else outcome.cost
        if outcome.status in STAGED:
            state.cumulative_cost += cost
            state.scene = outcome.scene_after
        else:  # skipped: nothing was staged, so the next trial starts where this one would have
            cost = 0.0
        yield _scored(trial, task, staged, outcome, cost, state.cumulative_cost, started_at)


def _axis(task: Task, perturbation: str | None) -> str | None:
    return None if perturbation is None else task.perturbations.get(perturbation).axis


def _skipped(trial: PlannedTrial, task: Task, cumulative: float) -> TrialRecord:
    return TrialRecord(
        index=trial.index,
        base_id=trial.base.id,
        perturbation=trial.perturbation,
        axis=_axis(task, trial.perturbation),
        family=trial.base.family,
        staging="not_applicable",
        repeat=trial.repeat,
        status="not_applicable",
        instance=None,
        cost=0.0,
        cumulative_cost=cumulative,
    )


def _scored(
    trial: PlannedTrial, task: Task, staged: Staged, outcome: Outcome, cost: float, cumulative: float, started_at: str
) -> TrialRecord:
    instance = staged.instance
    assert instance is not None
    reference = outcome.reference_length
    return TrialRecord(
        index=trial.index,
        base_id=trial.base.id,
        perturbation=trial.perturbation,
        axis=_axis(task, trial.perturbation),
        family=instance.family,
        staging=staged.staging,
        repeat=trial.repeat,
        status=outcome.status,
        instance=instance,
        cost=cost,
        cumulative_cost=cumulative,
        success=outcome.success,
        spl=None if reference is None else spl(outcome.success, reference, outcome.path_length),
        progress=outcome.progress if outcome.progress is not None else float(outcome.success),
        path_length=outcome.path_length,
        reference_length=reference,
        steps=outcome.steps,
        duration_s=outcome.duration_s,
        started_at=started_at,
        scene_after=outcome.scene_after,
        rerun_path=outcome.rerun_path,
        dataset_episode=outcome.dataset_episode,
        extra=dict(outcome.extra),
    )


def assume_unchanged(context: TrialContext) -> Outcome:
    """A dry-run stand-in for execution: the robot leaves the scene exactly as it was staged."""
    return Outcome(success=False, steps=0, path_length=0.0, scene_after=context.instance.scene, duration_s=0.0)
