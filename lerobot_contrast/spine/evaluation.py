"""The spine: an `Evaluation` says what to run, on what, and where to record it; `run(evaluation)` stages, executes
and scores each planned trial in order, and owns the run's journal, results and summary."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import nullcontext
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from lerobot_contrast.contrast.adaptive import next_trial
from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.metrics import scored
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.staging import Staged, materialize, trial_rng
from lerobot_contrast.contrast.stopping import Monitor, StopRule
from lerobot_contrast.contrast.strategy import PlannedTrial, exceeds_budget
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import Outcome, TrialContext, TrialRecord
from lerobot_contrast.operators.base import Operator
from lerobot_contrast.policies.base import Policy
from lerobot_contrast.record.lost_trials import drop_lost_trials
from lerobot_contrast.record.observer import EpisodeObserver
from lerobot_contrast.record.plan_file import keep_plan
from lerobot_contrast.record.results import write_results
from lerobot_contrast.record.run_dir import RunDir, disk_full_said, open_run_dir
from lerobot_contrast.record.summary import summarize
from lerobot_contrast.record.third_party import third_party_output
from lerobot_contrast.spine.runner import RobotRunner
from lerobot_contrast.terminal.lines import trial_line

if TYPE_CHECKING:
    from lerobot.robots import Robot

Execute = Callable[[TrialContext], Outcome]
# Trials whose staging was paid for: the scene they left behind is where the next one starts.
STAGED = ("done", "aborted")


class BudgetError(UserError):
    pass


@dataclass
class Evaluation:
    """One contrast-set evaluation. Give `robot` (a connected LeRobot robot) and `policy`, or `execute`, a stand-in
    that runs one trial and reports its `Outcome`. With `output_dir`, the run is recorded there (and resumable)."""

    task: Task
    plan: list[PlannedTrial]
    cost_model: CostModel
    budget: float | None = None  # stop once the cumulative cost exceeds it (None: run the whole plan)
    seed: int = 0
    policy: Policy | None = None
    robot: Robot = None
    observers: Sequence[EpisodeObserver] = ()  # watch each episode the robot runs, then get its scored record
    operator: Operator | None = None  # None: the robot stages and reports its own scene (a simulator)
    fps: float | None = None  # control rate; None: as fast as the robot steps
    max_steps: int = 200
    max_episode_s: float | None = None
    execute: Execute | None = None
    output_dir: Path | None = None
    resume: bool = False  # continue the run in `output_dir` from its journal
    rerun_aborted: bool = True  # on resume, run again the last trials a lost robot aborted (False: keep them)
    config: Mapping[str, Any] = field(default_factory=dict)  # written to config.json
    # Every setting's default, in config.json's form: a setting a run's config.json lacks (it was added after the
    # run started) counts as its default on resume.
    config_defaults: Mapping[str, Any] = field(default_factory=dict)
    labels: Mapping[str, Any] = field(default_factory=dict)  # e.g. strategy and policy, for the summary and logs
    verbose: bool = False  # print a line per trial (with `progress`: the run's notes, and `progress` shows trials)
    progress: Callable[[TrialRecord], None] | None = None  # told of each trial once recorded (progress.RunProgress)
    stop: StopRule | None = None  # sequential stopping rules, checked after every trial
    adaptive: bool = False  # --order=adaptive: each next trial is chosen from the outcomes so far (adaptive.py)
    lanes: int = 1  # simulated chains of trials run side by side (lane_runner.py), with the same results as one
    policy_for: Callable[[Any], Policy] | None = None  # the policy for another lane's robot (None: a copy)
    lane_threads: int = 1  # threads that answer the lanes (lane_choice.lane_threads)
    shared_episodes: Any = None  # episodes shared with a sweep's other cells (record/shared_episodes.py)

    @property
    def settings(self) -> dict[str, Any]:
        """What the summary and every episode's recording say about the run."""
        return {
            "task": self.task.name,
            "strategy": self.labels.get("strategy"),
            "policy": self.labels.get("policy", getattr(self.policy, "name", None)),
            "robot": getattr(self.robot, "name", None),
            "seed": self.seed,
            "cost_unit": self.cost_model.unit,
            "budget": self.budget,
            "planned_trials": len(self.plan),
        }


@dataclass
class Results:
    """What `run` returns: every trial's record and the summary (also in the run directory, where there is one)."""

    records: list[TrialRecord]
    summary: dict[str, Any]
    run_dir: Path | None = None


@dataclass
class LoopState:
    """Where the evaluation stands: the scene the robot left behind and the effort spent so far."""

    scene: Scene
    cumulative_cost: float = 0.0
    previous: Staged | None = None
    next_index: int = 0
    history: list[TrialRecord] = field(default_factory=list)  # the records so far, for --order=adaptive

    @classmethod
    def resume(cls, records: list[TrialRecord], initial_scene: Scene) -> LoopState:
        state = cls(scene=initial_scene, next_index=len(records), history=list(records))
        for record in records:
            state.previous = Staged(record.instance, record.staging)
            if record.status in STAGED and record.scene_after is not None:
                state.scene = record.scene_after
                state.cumulative_cost = record.cumulative_cost
        return state


def run(evaluation: Evaluation) -> Results:
    """Run the plan (from where its journal stopped, with `resume`) and write the results and summary, also
    when it is interrupted (then marked incomplete). The run directory is locked while it runs."""
    ev = evaluation
    if ev.output_dir is None:
        return _run(ev, None)
    path = Path(ev.output_dir)
    with (
        disk_full_said(path, f"resume with --output_dir={path} --resume=true"),
        open_run_dir(path, dict(ev.config), ev.resume, defaults=ev.config_defaults) as run_dir,
    ):
        _continue_from_journal(ev, run_dir)
        return _run(ev, run_dir)


def _continue_from_journal(ev: Evaluation, run_dir: RunDir) -> None:
    """Check that the plan and the journal are this run's, then bring the observers' files in line with it."""
    journal = run_dir.journal
    if journal.torn_bytes and ev.verbose:
        print(f"{journal.path}: dropped its last line, cut off mid-write by a kill; that trial runs again")
    keep_plan(run_dir.path, ev.plan)  # first: an edited config.json gives another plan, and this names it
    journal.check_planned(replay(ev, journal.records), len(ev.plan))
    if ev.rerun_aborted:
        drop_lost_trials(journal, _say if ev.verbose else None)
    for observer in ev.observers:
        observer.rollback(journal.records)


def _run(ev: Evaluation, run_dir: RunDir | None) -> Results:
    records: list[TrialRecord] = [] if run_dir is None else run_dir.journal.records
    state = LoopState.resume(records, ev.task.storage_scene())
    if records and ev.verbose:
        print(
            f"resuming {run_dir.path} at trial {state.next_index + 1} ({state.cumulative_cost:.2f} {ev.cost_model.unit} spent)"
        )
    complete = False
    monitor = None if ev.stop is None else Monitor(ev.plan, ev.stop)
    for record in records if monitor is not None else ():  # the sequential test as the journal left it
        monitor.observe(record)
    quiet = nullcontext() if run_dir is None else third_party_output(run_dir.path)
    with quiet:
        execute = None
        try:
            watching = ev.observers if ev.execute is None else ()  # observers watch the episodes a RobotRunner runs
            execute = _executor(ev, state)
            executed = trials(ev, state, execute, watching)
            for record in executed if monitor is None else _sequential(ev, monitor, executed):
                if run_dir is None:
                    records.append(record)
                else:
                    run_dir.journal.append(record)
                if ev.progress is not None:
                    ev.progress(record)
                elif ev.verbose:
                    print(trial_line(record, ev.cost_model.unit), flush=True)
            complete = True
        finally:
            getattr(execute, "close", lambda: None)()
            stopping = None if monitor is None else monitor.report(planned_end=complete)
            summary = summarize(records, settings=ev.settings, complete=complete, stopping=stopping)
            try:
                if run_dir is not None:
                    _write(run_dir, records, summary, ev.settings)
            finally:
                for observer in ev.observers:
                    observer.close()
    return Results(records, summary, None if run_dir is None else run_dir.path)


def _sequential(ev: Evaluation, monitor: Monitor, executed: Iterator[TrialRecord]) -> Iterator[TrialRecord]:
    """Check the stopping rules after every trial. Each record carries the sequential state it leaves in
    extra["sequential"], so the journal holds it; the run ends after the trial that decides."""
    if monitor.reason is not None:
        return
    for record in executed:
        closed = monitor.bases
        reason = monitor.observe(record)
        yield dataclasses.replace(record, extra={**record.extra, "sequential": monitor.state()})
        if ev.verbose and monitor.bases > closed:
            print(f"{'':>7}{monitor.line()}", flush=True)
        if reason is not None:
            return


def replay(evaluation: Evaluation, records: Sequence[TrialRecord]) -> list[TrialRecord]:
    """The records the plan gives when each trial ends as `records` say it did: what the journal of this
    evaluation must hold, up to timing and recordings."""
    replayed: list[TrialRecord] = []
    if not records:
        return replayed
    state = LoopState(evaluation.task.storage_scene())
    for record in trials(evaluation, state, lambda context: _recorded(records[context.index], context)):
        replayed.append(record)
        if len(replayed) == len(records):
            break
    return replayed


def _recorded(record: TrialRecord, context: TrialContext) -> Outcome:
    """The outcome `record` was scored from."""
    return Outcome(
        success=bool(record.success),
        steps=record.steps or 0,
        path_length=record.path_length or 0.0,
        scene_after=record.scene_after or context.current,
        duration_s=record.duration_s or 0.0,
        progress=record.progress,
        reference_length=record.reference_length,
        status=record.status,
        cost=record.cost,
        extra=record.extra,
    )


def _executor(ev: Evaluation, state: LoopState) -> Execute:
    if ev.execute is not None:
        return ev.execute
    if ev.robot is None or ev.policy is None:
        raise UserError("an Evaluation needs a robot and a policy, or `execute` to run each trial")
    if ev.lanes > 1 and ev.operator is None and not ev.adaptive and getattr(ev.robot, "simulated", False):
        from lerobot_contrast.lanes.runner import LaneRunner

        return LaneRunner(
            ev.task, ev.plan[state.next_index :], ev.seed, (state.scene, state.previous), ev.robot, ev.lanes,
            ev.policy, lambda robot, seat, observers: _runner(ev, robot, seat, observers),
            lambda trial, staged, scene: _context(ev, trial, staged, scene),
            ev.observers, ev.policy_for, ev.lane_threads,
        )  # fmt: skip
    return _runner(ev, ev.robot, ev.policy, ev.observers)


def _runner(ev: Evaluation, robot: Robot, policy: Policy, observers: Sequence[EpisodeObserver]) -> RobotRunner:
    return RobotRunner(
        robot,
        policy,
        ev.task,
        operator=ev.operator,
        fps=ev.fps,
        max_steps=ev.max_steps,
        max_episode_s=ev.max_episode_s,
        observers=observers,
        cost_unit=ev.cost_model.unit,
        cost_model=ev.cost_model,
        say=_say if ev.verbose else None,
        shared=ev.shared_episodes,
    )


def _say(line: str) -> None:
    print(line, flush=True)


def _write(run_dir: RunDir, records: list[TrialRecord], summary: dict[str, Any], settings: dict[str, Any]) -> None:
    write_results(run_dir.results_path, records, {k: str(v) for k, v in settings.items()})
    run_dir.write_summary(summary)


def preview(evaluation: Evaluation) -> list[TrialRecord]:
    """The plan's trials as they would run if the robot left every scene exactly as it was staged (--dry_run)."""
    state = LoopState(evaluation.task.storage_scene())
    return list(trials(evaluation, state, assume_unchanged))


def check_budget(evaluation: Evaluation) -> None:
    """Refuse a budget that cannot pay for staging the first trial."""
    ev, initial = evaluation, evaluation.task.storage_scene()
    if ev.budget is None or not ev.plan:
        return
    unit = ev.cost_model.unit
    if ev.budget <= 0:
        raise BudgetError(f"--budget must be positive ({unit}), got {ev.budget}")
    first = materialize(ev.plan[0], ev.task, initial, None, trial_rng(ev.seed, 0))
    if first.instance is None:
        return
    cost = ev.cost_model(initial, first.instance.scene)
    if ev.budget < cost:
        raise BudgetError(
            f"--budget {ev.budget:g} {unit} is below the cost of staging the first trial "
            f"({cost:.2f} {unit}); raise --budget or drop it for no limit"
        )


def trials(
    evaluation: Evaluation, state: LoopState, execute: Execute, observers: Sequence[EpisodeObserver] = ()
) -> Iterator[TrialRecord]:
    """Execute the plan from `state.next_index`, yielding one scored record per trial, until done or over budget.
    `observers` (those watching the episodes `execute` runs) receive each record and name their files in it."""
    ev = evaluation
    settings = ev.settings
    for trial in _upcoming(ev, state):
        if exceeds_budget(state.cumulative_cost, ev.budget):
            return
        staged = materialize(trial, ev.task, state.scene, state.previous, trial_rng(ev.seed, trial.index))
        state.previous = staged
        state.next_index = trial.index + 1
        if staged.instance is None:
            yield _not_applicable(trial, ev.task, state.cumulative_cost)
            continue
        context = _context(ev, trial, staged, state.scene, settings)
        started_at = datetime.now(UTC).isoformat(timespec="seconds")
        outcome = execute(context)
        cost = context.planned_cost if outcome.cost is None else outcome.cost
        if outcome.status in STAGED:
            state.cumulative_cost += cost
            state.scene = outcome.scene_after
        else:  # skipped: nothing was staged, so the next trial starts where this one would have
            cost = 0.0
        record = scored(context, outcome, cost, state.cumulative_cost, started_at)
        state.history.append(record)
        yield _observed(record, observers) if outcome.status in STAGED else record


def _context(
    ev: Evaluation, trial: PlannedTrial, staged: Staged, current: Scene, settings: dict[str, Any] | None = None
) -> TrialContext:
    """What the runner and the observers know of `trial`, staged as `staged` from the scene `current`."""
    return TrialContext(
        index=trial.index,
        instance=staged.instance,
        base=trial.base,
        current=current,
        planned_cost=ev.cost_model(current, staged.instance.scene),
        staging=staged.staging,
        rng=np.random.default_rng([ev.seed, trial.index, 1]),
        planned_trials=len(ev.plan),
        axis=_axis(ev.task, trial.perturbation),
        settings=ev.settings if settings is None else settings,
        repeat=trial.repeat,
    )


def _upcoming(ev: Evaluation, state: LoopState) -> Iterator[PlannedTrial]:
    """The plan from `state.next_index`; with adaptive order, each next trial as the outcomes so far choose it."""
    if not ev.adaptive:
        yield from ev.plan[state.next_index :]
        return
    while (trial := next_trial(ev.plan, state.history, lambda t: _staging_cost(ev, state, t))) is not None:
        yield trial


def _staging_cost(ev: Evaluation, state: LoopState, trial: PlannedTrial) -> float | None:
    """What staging `trial` from the current scene costs, None where it does not apply there."""
    staged = materialize(trial, ev.task, state.scene, state.previous, trial_rng(ev.seed, trial.index))
    return None if staged.instance is None else ev.cost_model(state.scene, staged.instance.scene)


def _observed(record: TrialRecord, observers: Sequence[EpisodeObserver]) -> TrialRecord:
    """The record with the files the observers wrote for its episode."""
    for observer in observers:
        files = observer.end(record)
        if files.rerun_path is not None:
            record = dataclasses.replace(record, rerun_path=files.rerun_path)
        if files.dataset_episode is not None:
            record = dataclasses.replace(record, dataset_episode=files.dataset_episode)
    return record


def _axis(task: Task, perturbation: str | None) -> str | None:
    return None if perturbation is None else task.perturbations.get(perturbation).axis


def _not_applicable(trial: PlannedTrial, task: Task, cumulative: float) -> TrialRecord:
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


def assume_unchanged(context: TrialContext) -> Outcome:
    """A dry-run stand-in for execution: the robot leaves the scene exactly as it was staged."""
    return Outcome(success=False, steps=0, path_length=0.0, scene_after=context.instance.scene, duration_s=0.0)
