"""Build a run's parts from its config: the robot, the policy, the operator console, the episode observers
and the runner that drives them."""

from __future__ import annotations

import importlib
import pkgutil
import sys
from pathlib import Path
from typing import Any

from lerobot_contrast.config import ConfigError, EvalConfig
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.operator_console import Answers, OperatorConsole
from lerobot_contrast.runners.episode import EpisodeObserver, reports_scene
from lerobot_contrast.runners.robot import RobotRunner

# The robot each task runs on when no --robot is given: a simulator, or the LoCoBot host's sim backend.
TASK_ROBOTS = {"language_table": "language_table_sim", "vln": "locobot"}
OPERATORS = ("auto", "console")
DEFAULT_HARDWARE_FPS = 10.0


def register_robots() -> dict[str, str]:
    """Make every robot type known before parsing: LeRobot's own robots and cameras, its plugins and this
    package's simulated robots. Returns the built-in packages that could not be imported here, with why."""
    from lerobot.utils.import_utils import register_third_party_plugins

    import lerobot_contrast.sims.language_table.config_language_table_sim  # noqa: F401

    unavailable = {}
    for family in ("lerobot.robots", "lerobot.cameras"):
        for module in pkgutil.iter_modules(importlib.import_module(family).__path__):
            if module.ispkg:
                try:
                    importlib.import_module(f"{family}.{module.name}")
                except ImportError as error:  # a robot whose optional SDK is not installed
                    unavailable[module.name] = str(error)
    register_third_party_plugins()
    return unavailable


def check_robot_type(argv: list[str], unavailable: dict[str, str]) -> None:
    """Name the known robot types when --robot.type is not one of them, instead of argparse's usage dump."""
    from lerobot.robots import RobotConfig

    given = [arg.split("=", 1)[1] for arg in argv if arg.startswith("--robot.type=")]
    known = sorted(RobotConfig.get_known_choices())
    for robot_type in given:
        if robot_type not in known:
            missing = "".join(f"; {name} could not be imported ({why})" for name, why in unavailable.items())
            raise ConfigError(
                f"--robot.type={robot_type} is not a known robot; known: {', '.join(known)}. A plugin robot "
                f"needs its package installed (pip install lerobot_robot_{robot_type}){missing}"
            )


def needs_camera(cfg: EvalConfig) -> bool:
    """Scripted policies read the scene, not images: render only for a learned policy or a recording."""
    return cfg.policy.kind == "lerobot" or cfg.rerun or cfg.record_dataset


def choose_robot(cfg: EvalConfig) -> None:
    """Fill in the task's own robot when --robot is not given, so the run's config.json names it."""
    from lerobot.robots import RobotConfig

    if cfg.robot is not None:
        return
    if cfg.task not in TASK_ROBOTS:
        raise ConfigError(f"--task={cfg.task} has no simulator; name your robot with --robot.type=...")
    robot_class = RobotConfig.get_choice_class(TASK_ROBOTS[cfg.task])
    cfg.robot = robot_class(camera=needs_camera(cfg)) if cfg.task == "language_table" else robot_class()


def make_robot(cfg: EvalConfig) -> Any:
    from lerobot.robots import make_robot_from_config

    choose_robot(cfg)
    try:
        return make_robot_from_config(cfg.robot)
    except Exception as error:
        raise ConfigError(
            f"--robot.type={cfg.robot.type}: cannot build the robot ({' '.join(str(error).split())})"
        ) from None


def make_policy(cfg: EvalConfig, robot: Any, task: Any, plan: list[PlannedTrial]) -> Any:
    kind = cfg.policy.kind
    if kind == "lerobot":
        from lerobot_contrast.pretrained_policy import PretrainedPolicy

        return PretrainedPolicy(
            robot, cfg.policy.path, cfg.policy.type, cfg.policy.device, cfg.rename_map, cfg.policy.use_amp
        )
    if kind == "route_follower":
        return _route_follower(cfg, robot, task)
    return _tabletop_policy(cfg, robot, task, plan)


def _route_follower(cfg: EvalConfig, robot: Any, task: Any) -> Any:
    from lerobot_contrast.tasks.vln import VLNTask
    from lerobot_contrast.tasks.vln.policy import RouteFollower

    if not isinstance(task, VLNTask) or not hasattr(robot.config, "forward_m"):
        raise ConfigError("--policy.type=route_follower navigates --task=vln on --robot.type=locobot only")
    return RouteFollower(robot.config.forward_m, robot.config.turn_deg, cfg.policy.language_blind)


def _tabletop_policy(cfg: EvalConfig, robot: Any, task: Any, plan: list[PlannedTrial]) -> Any:
    from lerobot_contrast.policies import OraclePolicy, RandomPolicy
    from lerobot_contrast.tasks.language_table import LanguageTableTask
    from lerobot_contrast.tasks.language_table.board import MAX_ACTION

    kind = cfg.policy.kind
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


def make_observers(cfg: EvalConfig, task: Any, robot: Any, run_dir: Path) -> list[EpisodeObserver]:
    observers: list[EpisodeObserver] = []
    if cfg.rerun:
        from lerobot_contrast.record.rerun_log import RerunEpisodeRecorder

        observers.append(RerunEpisodeRecorder(run_dir, task=task))
    if cfg.record_dataset:
        from lerobot_contrast.record.dataset import DatasetRecorder

        fps = round(cfg.fps or DEFAULT_HARDWARE_FPS)  # a simulator's control rate, however fast it is stepped
        observers.append(DatasetRecorder(run_dir, fps=fps, robot_type=robot.name))
    return observers


def make_runner(
    cfg: EvalConfig, robot: Any, task: Any, policy: Any, unit: str, observers: list[EpisodeObserver]
) -> RobotRunner:
    scene_io = reports_scene(robot, task.storage_scene().objects)
    mode = cfg.operator or ("auto" if scene_io else "console")
    if mode not in OPERATORS:
        raise ConfigError(f"--operator: unknown mode {mode!r}; choose from: {', '.join(OPERATORS)}")
    if mode == "auto" and not scene_io:
        raise ConfigError(
            f"--operator=auto needs a robot that reports and stages this task's scene; {robot.name} cannot, "
            "so use --operator=console"
        )
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
        observers=observers,
        cost_unit=unit,
        scene_io=scene_io,
    )
