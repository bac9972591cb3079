"""Checking an evaluation's flags, planning it and equipping its `Evaluation`: the parts that the single-policy
command, the interleaved `--policies` command and the sweep share."""

from __future__ import annotations

import dataclasses
import json
import math
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lerobot_contrast.clock.robot_clock import check_clock
from lerobot_contrast.contrast.cost import CostModel, RobotTimeCost
from lerobot_contrast.contrast.stopping import StopRule
from lerobot_contrast.contrast.strategy import PlannedTrial, make_plan
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.domains import load_task
from lerobot_contrast.lanes.choice import choose_lanes, lane_threads, parse_lanes
from lerobot_contrast.operators.base import Operator
from lerobot_contrast.policies import Policy, default_policy, make_policy
from lerobot_contrast.record.compare_run import compare_rule
from lerobot_contrast.record.plan_file import PLAN_SETTINGS, check_same_plan
from lerobot_contrast.spine.build import (
    OPERATORS,
    make_observers,
    run_fps,
)
from lerobot_contrast.spine.config import ConfigError, EvalConfig, config_json
from lerobot_contrast.terminal.lines import plan_lines

if TYPE_CHECKING:
    from lerobot.robots import Robot

    from lerobot_contrast.spine.evaluation import Evaluation


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
    check_clock(cfg.clock)
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


def check_new_run_dir(cfg: EvalConfig) -> None:
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
    cost = run_cost_model(task, cfg)  # cost_aware order prices staging in the run's own cost model
    return task, make_plan(cfg.strategy, instances, perturbations, cfg.repeats, rng, cfg.order, cost)


def default_output_dir(cfg: EvalConfig, task: Task) -> Path:
    now = datetime.now()
    return Path("outputs/contrast") / now.strftime("%Y-%m-%d") / f"{now:%H-%M-%S}_{task.name}_{cfg.strategy}"


def dry_run(evaluation: Evaluation) -> None:
    from lerobot_contrast.spine.evaluation import preview

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


def connect(robot: Robot, clock: str = "wall") -> None:
    """Connect `robot` running on `clock` (--clock), its cameras then read on that clock."""
    from lerobot_contrast.clock.robot_clock import use_clock

    chosen = use_clock(clock)  # a twin's clock that does not answer is one line before the robot connects
    try:
        robot.connect()
        chosen.watch(robot)
    except Exception as error:
        # The type the user gave (so101_follower), not the class's name, which LeRobot shares (so_follower).
        given = getattr(getattr(robot, "config", None), "type", robot.name)
        raise ConfigError(
            f"--robot.type={given}: cannot connect ({' '.join(str(error).split())}); "
            "check that it is powered and reachable, and its --robot.* settings"
        ) from None


def planned_evaluation(cfg: EvalConfig) -> Evaluation:
    """The checked plan as an Evaluation with no robot, policy or run directory attached yet."""
    # The spine loads its runner, which loads LeRobot and torch: only once the flags are known to be sound.
    from lerobot_contrast.spine.evaluation import Evaluation, check_budget

    source = adopt_plan(cfg) if cfg.plan else None
    validate(cfg)
    task, plan = build_plan(cfg)
    if source is not None:
        check_same_plan(source, plan)
    planned = Evaluation(
        task, plan, run_cost_model(task, cfg), cfg.budget, cfg.seed, stop=stop_rule(cfg, plan),
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
    cfg: EvalConfig, planned: Evaluation, robot: Robot, policy: Policy, operator: Operator | None
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


def run_cost_model(task: Task, cfg: EvalConfig) -> CostModel:
    """The task's `--cost` model; robot time planned as one pick and place per moved object at the arm's --arm.pace."""
    cost = task.cost_model(cfg.cost)
    if isinstance(cost, RobotTimeCost):
        from lerobot_contrast.so101 import PICK_AND_PLACE_S

        cost = dataclasses.replace(cost, per_object_s=PICK_AND_PLACE_S * cfg.arm.pace)
    return cost
