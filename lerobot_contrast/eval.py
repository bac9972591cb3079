"""`python -m lerobot_contrast.eval`: plan, run, record and summarise a contrast-set evaluation."""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lerobot_contrast.build import (
    OPERATORS,
    check_robot_type,
    make_observers,
    make_operator,
    make_robot,
    register_robots,
    run_fps,
)
from lerobot_contrast.config import ConfigError, EvalConfig, config_json, resume_args
from lerobot_contrast.console import plan_lines
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.stopping import StopRule, summary_line
from lerobot_contrast.contrast.strategy import PlannedTrial, make_plan
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.domains import load_task
from lerobot_contrast.flags import (
    bool_flags,
    check_names,
    flag_names,
    help_text,
    join_values,
    parse_config,
    robot_type,
    wants_help,
)
from lerobot_contrast.lane_choice import choose_lanes, lane_threads, parse_lanes, use_threads
from lerobot_contrast.operator_console import OperatorConsole, SessionStopped
from lerobot_contrast.policies import Policy, default_policy, make_policy
from lerobot_contrast.progress import RunProgress, header_lines
from lerobot_contrast.record.compare_run import compare_rule
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.record.plan_file import PLAN_SETTINGS, check_same_plan

if TYPE_CHECKING:
    from lerobot.robots import Robot

    from lerobot_contrast.evaluation import Evaluation


# Base instances times repeats one run may plan: beyond this, planning alone takes minutes and gigabytes.
MAX_BASE_TRIALS = 10_000


def validate(cfg: EvalConfig) -> None:
    """Refuse every flag value that cannot make a sound run, before anything is planned, connected or written."""
    for name, value in (("n_instances", cfg.n_instances), ("max_episode_steps", cfg.max_episode_steps)):
        if value is not None and value < 1:
            raise ConfigError(f"--{name} must be at least 1, got {value}")
    if cfg.repeats < 1:
        raise ConfigError(f"--repeats must be at least 1, got {cfg.repeats}")
    if cfg.seed < 0:
        raise ConfigError(f"--seed must be a whole number >= 0, got {cfg.seed}")
    for name, value in (("fps", cfg.fps), ("max_episode_s", cfg.max_episode_s)):
        _check_positive(name, value, "leave it out for the default")
    _check_positive("budget", cfg.budget, "drop --budget for no limit")
    for name, values in (("perturbations", cfg.perturbations), ("families", cfg.families)):
        repeated = sorted({v for v in values or () if list(values).count(v) > 1})
        if repeated:
            raise ConfigError(f"--{name}: {', '.join(repeated)} given more than once; name each once")
    if cfg.operator is not None and cfg.operator not in OPERATORS:
        raise ConfigError(f"--operator: unknown mode {cfg.operator!r}; choose from: {', '.join(OPERATORS)}")
    _check_policy_args(cfg)
    parse_lanes(cfg.lanes)
    _check_run_dir(cfg)
    if cfg.push_to_hub and cfg.repo_id is None:
        raise ConfigError("--push_to_hub needs --repo_id=USER/NAME naming the Hub dataset repo to publish to")
    if cfg.repo_id is not None:
        from lerobot_contrast.record.hub import check_repo_id

        check_repo_id(cfg.repo_id)
    if cfg.perturbations is not None and cfg.strategy != "contrast":
        raise ConfigError(f"--perturbations only applies to --strategy=contrast, not {cfg.strategy!r}")


def _check_positive(name: str, value: float | None, otherwise: str) -> None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise ConfigError(f"--{name} must be a positive number, got {value:g}; {otherwise}")


def _check_policy_args(cfg: EvalConfig) -> None:
    noise, blind = cfg.policy.noise_std, cfg.policy.language_blind
    if not (math.isfinite(noise) and noise >= 0):
        raise ConfigError(f"--policy.noise_std must be a number of metres >= 0, got {noise:g}")
    if not 0 <= blind <= 1:
        raise ConfigError(f"--policy.language_blind is a probability between 0 and 1, got {blind:g}")
    from lerobot_contrast.policies.pretrained import looks_like_path

    path = cfg.policy.path  # checked here so that a dry run, and a sweep's, names a policy that is not there
    if path is not None and looks_like_path(path) and not Path(path).expanduser().is_dir():
        raise ConfigError(
            f"--policy.path: no such directory: {path}; give a directory written by save_pretrained or a Hub repo id"
        )


def _check_run_dir(cfg: EvalConfig) -> None:
    if cfg.resume and cfg.output_dir is None:
        raise ConfigError("--resume needs --output_dir naming the run directory to continue")
    if cfg.output_dir is not None and cfg.output_dir.exists() and not cfg.output_dir.is_dir():
        raise ConfigError(f"--output_dir: {cfg.output_dir} is a file, not a directory; choose a directory")


def _check_new_run_dir(cfg: EvalConfig) -> None:
    path = cfg.output_dir
    if not cfg.resume and path is not None and path.is_dir() and any(path.iterdir()):
        raise ConfigError(
            f"--output_dir: {path} already exists; pass --resume=true to continue that run or choose a new directory"
        )


def build_plan(cfg: EvalConfig) -> tuple[Task, list[PlannedTrial]]:
    """The task and the ordered trials; depends only on the config, so a resumed run rebuilds the same plan."""
    task = load_task(cfg.task, families=cfg.families)
    perturbations = task.perturbations.select(cfg.perturbations) if cfg.strategy == "contrast" else []
    n_instances = cfg.n_instances or task.default_instances
    if n_instances * cfg.repeats > MAX_BASE_TRIALS:
        raise ConfigError(
            f"--n_instances={n_instances} with --repeats={cfg.repeats} asks for more than {MAX_BASE_TRIALS} "
            "base trials in one run; split the evaluation into runs with different --seed values"
        )
    rng = np.random.default_rng(cfg.seed)
    instances = task.sample(n_instances, rng)
    cost = task.cost_model(cfg.cost)  # cost_aware order prices staging in the run's own cost model
    return task, make_plan(cfg.strategy, instances, perturbations, cfg.repeats, rng, cfg.order, cost)


def default_output_dir(cfg: EvalConfig, task: Task) -> Path:
    now = datetime.now()
    return Path("outputs/contrast") / now.strftime("%Y-%m-%d") / f"{now:%H-%M-%S}_{task.name}_{cfg.strategy}"


def dry_run(evaluation: Evaluation) -> None:
    from lerobot_contrast.evaluation import preview

    records, unit = preview(evaluation), evaluation.cost_model.unit
    print("\n".join(plan_lines(records, evaluation.task.storage_scene(), evaluation.cost_model)))
    done = [r for r in records if r.status == "done"]
    total = done[-1].cumulative_cost if done else 0.0
    print(
        f"plan: {len(done)} trials ({len(records) - len(done)} not applicable) of {len(evaluation.plan)} planned, "
        f"planned cost {total:.2f} {unit} (assuming the robot leaves every scene as staged)"
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


def connect(robot: Robot) -> None:
    try:
        robot.connect()
    except Exception as error:
        raise ConfigError(
            f"--robot.type={robot.name}: cannot connect ({' '.join(str(error).split())}); "
            "check that it is powered and reachable, and its --robot.* settings"
        ) from None


def planned_evaluation(cfg: EvalConfig) -> Evaluation:
    """The checked plan as an Evaluation with no robot, policy or run directory attached yet."""
    # The spine loads its runner, which loads LeRobot and torch: only once the flags are known to be sound.
    from lerobot_contrast.evaluation import Evaluation, check_budget

    source = adopt_plan(cfg) if cfg.plan else None
    validate(cfg)
    task, plan = build_plan(cfg)
    if source is not None:
        check_same_plan(source, plan)
    planned = Evaluation(
        task, plan, task.cost_model(cfg.cost), cfg.budget, cfg.seed, stop=stop_rule(cfg, plan),
        adaptive=cfg.order == "adaptive",
    )  # fmt: skip
    check_budget(planned)
    return planned


def stop_rule(cfg: EvalConfig, plan: list[PlannedTrial]) -> StopRule | None:
    """The --stop.* rules, or None without any; a width or alpha outside (0, 1), or a --stop.compare run whose
    plan, task or metric differs, is refused in one line."""
    if cfg.stop.compare is not None:
        rule = compare_rule(cfg.stop.compare, plan, cfg.task, cfg.stop.width, cfg.stop.alpha)
    else:
        rule = StopRule(cfg.stop.width, cfg.stop.alpha)
    return dataclasses.replace(rule, originals_only=cfg.order == "adaptive") if rule.active else None


def equipped(
    cfg: EvalConfig, planned: Evaluation, robot: Robot, policy: Policy, operator: OperatorConsole | None
) -> Evaluation:
    """The planned evaluation with its connected robot, policy, operator and observers, recorded in cfg.output_dir."""
    fps = run_fps(cfg, robot)
    lanes = choose_lanes(
        cfg.lanes, robot, policy, operator=operator is not None, fps=fps, max_episode_s=cfg.max_episode_s
    )
    return dataclasses.replace(
        planned,
        policy=policy,
        robot=robot,
        observers=make_observers(cfg, planned.task, robot, cfg.output_dir),
        operator=operator,
        fps=fps,
        max_steps=cfg.max_episode_steps,
        max_episode_s=cfg.max_episode_s,
        output_dir=cfg.output_dir,
        resume=cfg.resume,
        rerun_aborted=cfg.rerun_aborted,
        config=config_json(cfg),
        config_defaults=config_json(EvalConfig()),
        labels={"strategy": cfg.strategy, "policy": cfg.policy.path or cfg.policy.type or default_policy(cfg.task)},
        verbose=True,
        lanes=lanes,
        lane_threads=lane_threads(lanes),
        policy_for=lambda lane_robot: make_policy(cfg.policy, lane_robot, planned.task, cfg.rename_map),
    )


def plan_and_run(cfg: EvalConfig, chosen_robot: str | None = None) -> int:
    """Plan, then either print the plan (--dry_run) or run it into a run directory; returns the exit code.
    `chosen_robot`: the --robot.type as given, for messages."""
    if cfg.policies is not None:
        from lerobot_contrast.pairing.command import run_policies

        return run_policies(cfg, chosen_robot)
    planned = planned_evaluation(cfg)
    task = planned.task
    if cfg.dry_run:
        dry_run(planned)
        return 0
    _check_new_run_dir(cfg)  # before the robot connects and the policy's weights load
    robot = make_robot(cfg, chosen_robot)
    # Connect before creating the run directory: an unreachable robot leaves nothing behind to resume.
    # A remote robot also says on connecting whether it can stage scenes.
    connect(robot)
    try:
        operator = make_operator(cfg, robot, task, planned.cost_model.unit)
        use_threads()  # chosen, not inherited from the machine (lane_choice.py)
        policy = make_policy(cfg.policy, robot, task, cfg.rename_map)  # one that cannot load leaves no run directory
        cfg.output_dir = cfg.output_dir or default_output_dir(cfg, task)
        return run_and_report(cfg, equipped(cfg, planned, robot, policy, operator))
    finally:
        if robot.is_connected:
            robot.disconnect()


def run_and_report(cfg: EvalConfig, evaluation: Evaluation) -> int:
    from lerobot_contrast.evaluation import run
    from lerobot_contrast.runner import RobotLostError

    path, unit = Path(evaluation.output_dir), evaluation.cost_model.unit
    resume = f"--output_dir={path} --resume=true"
    print("\n".join(header_lines(evaluation.settings, path, f"python -m lerobot_contrast.eval {resume}")), flush=True)
    journal = path / "journal.jsonl"
    already = read_journal(journal) if cfg.resume and journal.is_file() else []
    # The operator console prompts between trials, so a redrawn bar would tear its prompts: plain lines there.
    live = False if evaluation.operator is not None else None
    progress = RunProgress(len(evaluation.plan), unit, verbose=cfg.verbose, already=already, live=live)
    try:
        with progress:
            results = run(dataclasses.replace(evaluation, progress=progress))
    except KeyboardInterrupt:
        print(
            f"\ninterrupted: every finished trial is in {path / 'journal.jsonl'}; continue with {resume}",
            file=sys.stderr,
        )
        return 130
    except SessionStopped as stop:
        print(f"stopped: {stop}; {len(read_journal(path / 'journal.jsonl'))} trials recorded; continue with {resume}")
        return 0
    except RobotLostError as error:
        print(f"error: {error} with {resume}", file=sys.stderr)
        return 2
    from lerobot_contrast.reporting.run_table import results_table  # pandas and scipy, needed only now

    print(results_table(results.records, results.summary, unit))
    if "stopping" in results.summary:
        print(summary_line(results.summary["stopping"]))
    spent, ran = results.summary["overall"]["cumulative_cost"], len(results.records)
    if cfg.budget is not None and spent > cfg.budget:
        print(
            f"stopped at the budget: {spent:.2f} of {cfg.budget:g} {unit} spent, {ran} of {len(evaluation.plan)} planned trials reached"
        )
    print(f"run directory: {path}")
    if cfg.push_to_hub:
        from lerobot_contrast.record.hub import publish_run

        print(f"published: {publish_run(path, cfg.repo_id, private=cfg.private)}")
    return 0


def main(argv: list[str] | None = None) -> int:
    try:
        argv = join_values(list(sys.argv[1:] if argv is None else argv), bool_flags(EvalConfig))
        if not wants_help(argv):  # a mistyped flag is named before LeRobot, torch and the robot plugins load
            check_names(argv, flag_names(EvalConfig), robots=False)
        check_robot_type(argv, register_robots())
        if wants_help(argv):
            print(help_text(EvalConfig, "python -m lerobot_contrast.eval", robot_type(argv)))
            return 0
        return plan_and_run(parse_config(EvalConfig, resume_args(argv)), robot_type(argv))
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
