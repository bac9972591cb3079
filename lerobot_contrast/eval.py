"""`python -m lerobot_contrast.eval`: plan, run, record and summarise a contrast-set evaluation."""

from __future__ import annotations

import json
import sys
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from lerobot_contrast.build import (
    check_robot_type,
    make_observers,
    make_policy,
    make_robot,
    make_runner,
    register_robots,
)
from lerobot_contrast.config import ConfigError, EvalConfig, config_json, parse_config, resume_args
from lerobot_contrast.console import plan_lines, trial_line
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.strategy import PlannedTrial, make_plan
from lerobot_contrast.contrast.task import cost_model as task_cost_model
from lerobot_contrast.evaluate import LoopState, assume_unchanged, check_budget, run_trials
from lerobot_contrast.operator_console import SessionStopped
from lerobot_contrast.record.plan_file import PLAN_SETTINGS, check_same_plan, write_plan
from lerobot_contrast.record.results import write_results
from lerobot_contrast.record.run_dir import RunDir, open_run_dir
from lerobot_contrast.record.summary import format_summary, summarize
from lerobot_contrast.runners.robot import RobotLostError
from lerobot_contrast.tasks import make_task

DEFAULT_INSTANCES = 50


def validate(cfg: EvalConfig) -> None:
    if cfg.n_instances is not None and cfg.n_instances < 1:
        raise ConfigError(f"--n_instances must be at least 1, got {cfg.n_instances}")
    if cfg.max_episode_steps < 1:
        raise ConfigError(f"--max_episode_steps must be at least 1, got {cfg.max_episode_steps}")
    if cfg.resume and cfg.output_dir is None:
        raise ConfigError("--resume needs --output_dir naming the run directory to continue")
    if cfg.push_to_hub and cfg.repo_id is None:
        raise ConfigError("--push_to_hub needs --repo_id=USER/NAME naming the Hub dataset repo to publish to")
    if cfg.perturbations is not None and cfg.strategy != "contrast":
        raise ConfigError(f"--perturbations only applies to --strategy=contrast, not {cfg.strategy!r}")


def build_plan(cfg: EvalConfig) -> tuple[Any, list[PlannedTrial]]:
    """The task and the ordered trials; depends only on the config, so a resumed run rebuilds the same plan."""
    task = make_task(cfg.task, families=cfg.families)
    perturbations = task.perturbations.select(cfg.perturbations) if cfg.strategy == "contrast" else []
    rng = np.random.default_rng(cfg.seed)
    instances = task.sample(cfg.n_instances or getattr(task, "default_instances", DEFAULT_INSTANCES), rng)
    return task, make_plan(cfg.strategy, instances, perturbations, cfg.repeats, rng, cfg.order)


def default_output_dir(cfg: EvalConfig, task: Any) -> Path:
    now = datetime.now()
    return Path("outputs/contrast") / now.strftime("%Y-%m-%d") / f"{now:%H-%M-%S}_{task.name}_{cfg.strategy}"


def dry_run(cfg: EvalConfig, task: Any, plan: list[PlannedTrial], cost_model: Any) -> None:
    initial = task.storage_scene()
    records = list(run_trials(plan, task, cost_model, cfg.budget, cfg.seed, LoopState(initial), assume_unchanged))
    print("\n".join(plan_lines(records, initial, cost_model.unit)))
    done = [r for r in records if r.status == "done"]
    total = done[-1].cumulative_cost if done else 0.0
    print(
        f"plan: {len(done)} trials ({len(records) - len(done)} not applicable) of {len(plan)} planned, "
        f"planned cost {total:.2f} {cost_model.unit} (assuming the robot leaves every scene as staged)"
    )


def adopt_plan(cfg: EvalConfig) -> Path:
    """Take the plan-deciding settings of the run `--plan` names (downloaded first for hub:USER/NAME)."""
    from lerobot_contrast.record.hub import resolve_run

    source = resolve_run(cfg.plan)
    config_path = source / "config.json"
    if not config_path.exists():
        raise ConfigError(f"--plan: {cfg.plan} holds no config.json; give a run directory or hub:USER/NAME")
    published = json.loads(config_path.read_text(encoding="utf-8"))
    for key in PLAN_SETTINGS:
        if key in published:
            setattr(cfg, key, published[key])
    return source


def run(
    cfg: EvalConfig, task: Any, plan: list[PlannedTrial], cost_model: Any, run_dir: RunDir, robot: Any, policy: Any
) -> dict[str, Any]:
    observers = make_observers(cfg, task, robot, run_dir.path)
    execute = make_runner(cfg, robot, task, policy, cost_model.unit, observers)
    write_plan(run_dir.path, plan)
    records = run_dir.journal.records
    state = LoopState.resume(records, task.storage_scene())
    if records:
        print(
            f"resuming {run_dir.path} at trial {state.next_index} ({state.cumulative_cost:.2f} {cost_model.unit} spent)"
        )
    settings = {
        "task": task.name,
        "strategy": cfg.strategy,
        "policy": cfg.policy.label,
        "robot": robot.name,
        "seed": cfg.seed,
        "cost_unit": cost_model.unit,
        "budget": cfg.budget,
        "planned_trials": len(plan),
    }
    complete = False
    try:
        for record in run_trials(plan, task, cost_model, cfg.budget, cfg.seed, state, execute, settings):
            run_dir.journal.append(record)
            print(trial_line(record, cost_model.unit), flush=True)
        complete = True
    finally:
        summary = summarize(run_dir.journal.records, settings=settings, complete=complete)
        metadata = {k: str(v) for k, v in settings.items()}
        write_results(run_dir.results_path, run_dir.journal.records, metadata)
        run_dir.write_summary(summary)
        for observer in observers:
            observer.close()
    return summary


def connect(robot: Any) -> None:
    try:
        robot.connect()
    except Exception as error:
        raise ConfigError(
            f"--robot.type={robot.name}: cannot connect ({' '.join(str(error).split())}); "
            "check that it is powered and reachable, and its --robot.* settings"
        ) from None


def evaluate(cfg: EvalConfig) -> int:
    """Plan, then either print the plan (--dry_run) or run it into a run directory; returns the exit code."""
    source = adopt_plan(cfg) if cfg.plan else None
    validate(cfg)
    task, plan = build_plan(cfg)
    if source is not None:
        check_same_plan(source, plan)
    cost_model = task_cost_model(task, cfg.cost)
    check_budget(plan, task, cost_model, cfg.budget, cfg.seed, task.storage_scene())
    if cfg.dry_run:
        dry_run(cfg, task, plan, cost_model)
        return 0
    robot = make_robot(cfg)
    # Connect before creating the run directory: an unreachable robot leaves nothing behind to resume.
    # A remote robot also says on connecting whether it can stage scenes.
    connect(robot)
    try:
        policy = make_policy(cfg, robot, task, plan)  # a policy that cannot load leaves no run directory either
        cfg.output_dir = cfg.output_dir or default_output_dir(cfg, task)
        run_dir = open_run_dir(cfg.output_dir, config_json(cfg), cfg.resume)
        return run_and_report(cfg, task, plan, cost_model, run_dir, robot, policy)
    finally:
        if robot.is_connected:
            robot.disconnect()


def run_and_report(
    cfg: EvalConfig, task: Any, plan: list[PlannedTrial], cost_model: Any, run_dir: RunDir, robot: Any, policy: Any
) -> int:
    resume = f"--output_dir={run_dir.path} --resume=true"
    try:
        summary = run(cfg, task, plan, cost_model, run_dir, robot, policy)
    except KeyboardInterrupt:
        print(
            f"\ninterrupted: every finished trial is in {run_dir.journal.path}; continue with {resume}", file=sys.stderr
        )
        return 130
    except SessionStopped as stop:
        print(f"stopped: {stop}; {len(run_dir.journal.records)} trials recorded; continue with {resume}")
        return 0
    except RobotLostError as error:
        print(f"error: {error} with {resume}", file=sys.stderr)
        return 2
    print(format_summary(summary, cost_model.unit))
    spent, ran = summary["overall"]["cumulative_cost"], len(run_dir.journal.records)
    if cfg.budget is not None and spent > cfg.budget:
        print(
            f"stopped at the budget: {spent:.2f} of {cfg.budget:g} {cost_model.unit} spent, {ran} of {len(plan)} planned trials reached"
        )
    print(f"run directory: {run_dir.path}")
    if cfg.push_to_hub:
        from lerobot_contrast.record.hub import publish_run

        print(f"published: {publish_run(run_dir.path, cfg.repo_id, private=cfg.private)}")
    return 0


def main(argv: list[str] | None = None) -> int:
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        check_robot_type(argv, register_robots())
        return evaluate(parse_config(EvalConfig, resume_args(argv)))
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
