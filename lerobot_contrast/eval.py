"""`python -m lerobot_contrast.eval`: plan, run, record and summarise a contrast-set evaluation."""

from __future__ import annotations

import sys
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from lerobot_contrast.config import ConfigError, EvalConfig, config_json, parse_config
from lerobot_contrast.console import plan_lines, trial_line
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.strategy import PlannedTrial, make_plan
from lerobot_contrast.contrast.task import cost_model as task_cost_model
from lerobot_contrast.evaluate import LoopState, assume_unchanged, check_budget, run_trials
from lerobot_contrast.operator_console import Answers, OperatorConsole, SessionStopped
from lerobot_contrast.record.results import write_results
from lerobot_contrast.record.run_dir import RunDir, open_run_dir
from lerobot_contrast.record.summary import format_summary, summarize
from lerobot_contrast.runners.robot import RobotLostError, RobotRunner
from lerobot_contrast.tasks import make_task


def validate(cfg: EvalConfig) -> None:
    if cfg.n_instances < 1:
        raise ConfigError(f"--n_instances must be at least 1, got {cfg.n_instances}")
    if cfg.max_episode_steps < 1:
        raise ConfigError(f"--max_episode_steps must be at least 1, got {cfg.max_episode_steps}")
    if cfg.resume and cfg.output_dir is None:
        raise ConfigError("--resume needs --output_dir naming the run directory to continue")
    if cfg.perturbations is not None and cfg.strategy != "contrast":
        raise ConfigError(f"--perturbations only applies to --strategy=contrast, not {cfg.strategy!r}")


def build_plan(cfg: EvalConfig) -> tuple[Any, list[PlannedTrial]]:
    """The task and the ordered trials; depends only on the config, so a resumed run rebuilds the same plan."""
    task = make_task(cfg.task, families=cfg.families)
    perturbations = task.perturbations.select(cfg.perturbations) if cfg.strategy == "contrast" else []
    rng = np.random.default_rng(cfg.seed)
    instances = task.sample(cfg.n_instances, rng)
    return task, make_plan(cfg.strategy, instances, perturbations, cfg.repeats, rng, cfg.order)


def default_output_dir(cfg: EvalConfig, task: Any) -> Path:
    now = datetime.now()
    return Path("outputs/contrast") / now.strftime("%Y-%m-%d") / f"{now:%H-%M-%S}_{task.name}_{cfg.strategy}"


# The simulated robot each task runs on when no --robot is given.
TASK_ROBOTS = {"language_table": "language_table_sim"}
OPERATORS = ("auto", "console")
DEFAULT_HARDWARE_FPS = 10.0


def register_robots() -> None:
    """Make every robot type known before parsing: LeRobot's plugins and this package's simulated robots."""
    from lerobot.utils.import_utils import register_third_party_plugins

    import lerobot_contrast.sims.language_table.config_language_table_sim  # noqa: F401

    register_third_party_plugins()


def make_robot(cfg: EvalConfig) -> Any:
    from lerobot.robots import RobotConfig, make_robot_from_config

    if cfg.robot is None:
        if cfg.task not in TASK_ROBOTS:
            raise ConfigError(f"--task={cfg.task} has no simulator; name your robot with --robot.type=...")
        cfg.robot = RobotConfig.get_choice_class(TASK_ROBOTS[cfg.task])()
    try:
        return make_robot_from_config(cfg.robot)
    except Exception as error:
        raise ConfigError(
            f"--robot.type={cfg.robot.type}: cannot build the robot ({' '.join(str(error).split())})"
        ) from None


def make_policy(cfg: EvalConfig, robot: Any, task: Any, plan: list[PlannedTrial]) -> Any:
    from lerobot_contrast.policies import OraclePolicy, RandomPolicy
    from lerobot_contrast.pretrained_policy import PretrainedPolicy
    from lerobot_contrast.runners.episode import reports_scene
    from lerobot_contrast.tasks.language_table import LanguageTableTask
    from lerobot_contrast.tasks.language_table.board import MAX_ACTION

    kind = cfg.policy.kind
    if kind == "lerobot":
        return PretrainedPolicy(
            robot, cfg.policy.path, cfg.policy.type, cfg.policy.device, cfg.rename_map, cfg.policy.use_amp
        )
    if set(robot.action_features) != {"delta_x", "delta_y"}:
        raise ConfigError(
            f"--policy.type={kind} drives the simulated tabletop only; give --policy.path for {robot.name}"
        )
    if kind == "random":
        return RandomPolicy(list(robot.action_features), MAX_ACTION)
    if not (isinstance(task, LanguageTableTask) and reports_scene(robot)):
        raise ConfigError(
            "--policy.type=oracle solves Language-Table instructions in simulation only; "
            "use --policy.type=random or --policy.path"
        )
    bases = {trial.base.id: trial.base for trial in plan}
    return OraclePolicy(robot.read_scene, task, bases, cfg.policy.noise_std, cfg.policy.language_blind)


def make_runner(cfg: EvalConfig, robot: Any, task: Any, plan: list[PlannedTrial], unit: str) -> RobotRunner:
    from lerobot_contrast.runners.episode import reports_scene

    policy = make_policy(cfg, robot, task, plan)
    scene_io = reports_scene(robot, task.storage_scene().objects)
    mode = cfg.operator or ("auto" if scene_io else "console")
    if mode not in OPERATORS:
        raise ConfigError(f"--operator: unknown mode {mode!r}; choose from: {', '.join(OPERATORS)}")
    operator = OperatorConsole(Answers(sys.stdin), unit=unit) if mode == "console" else None
    # Simulated robots step as fast as they can unless asked for a rate; hardware runs at a fixed one.
    fps = cfg.fps if cfg.fps is not None else (None if getattr(robot, "simulated", False) else DEFAULT_HARDWARE_FPS)
    return RobotRunner(
        robot,
        policy,
        task,
        operator=operator,
        fps=fps,
        max_steps=cfg.max_episode_steps,
        max_episode_s=cfg.max_episode_s,
        cost_unit=unit,
        scene_io=scene_io,
    )


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


def run(cfg: EvalConfig, task: Any, plan: list[PlannedTrial], cost_model: Any, run_dir: RunDir) -> dict[str, Any]:
    robot = make_robot(cfg)
    execute = make_runner(cfg, robot, task, plan, cost_model.unit)
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
    connect(robot)
    try:
        for record in run_trials(plan, task, cost_model, cfg.budget, cfg.seed, state, execute, settings):
            run_dir.journal.append(record)
            print(trial_line(record, cost_model.unit), flush=True)
        complete = True
    finally:
        if robot.is_connected:
            robot.disconnect()
        summary = summarize(run_dir.journal.records, settings=settings, complete=complete)
        metadata = {k: str(v) for k, v in settings.items()}
        write_results(run_dir.results_path, run_dir.journal.records, metadata)
        run_dir.write_summary(summary)
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
    validate(cfg)
    task, plan = build_plan(cfg)
    cost_model = task_cost_model(task, cfg.cost)
    check_budget(plan, task, cost_model, cfg.budget, cfg.seed, task.storage_scene())
    if cfg.dry_run:
        dry_run(cfg, task, plan, cost_model)
        return 0
    cfg.output_dir = cfg.output_dir or default_output_dir(cfg, task)
    run_dir = open_run_dir(cfg.output_dir, config_json(cfg), cfg.resume)
    resume = f"--output_dir={run_dir.path} --resume=true"
    try:
        summary = run(cfg, task, plan, cost_model, run_dir)
    except KeyboardInterrupt:
        print(
            f"\ninterrupted: every finished trial is in {run_dir.journal.path}; continue with {resume}", file=sys.stderr
        )
        return 130
    except SessionStopped as stop:
        print(f"stopped: {stop}; {len(run_dir.journal.records)} trials recorded; continue with {resume}")
        return 0
    except RobotLostError as error:
        print(f"error: {error} ({resume})", file=sys.stderr)
        return 2
    print(format_summary(summary, cost_model.unit))
    spent, ran = summary["overall"]["cumulative_cost"], len(run_dir.journal.records)
    if cfg.budget is not None and spent > cfg.budget:
        print(
            f"stopped at the budget: {spent:.2f} of {cfg.budget:g} {cost_model.unit} spent, {ran} of {len(plan)} planned trials reached"
        )
    print(f"run directory: {run_dir.path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    try:
        register_robots()
        return evaluate(parse_config(EvalConfig, argv))
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
